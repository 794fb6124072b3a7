#pragma once
// Bus over LCM (udpm://, memq://, file://). See bus.hpp.
#include <lcm/lcm-cpp.hpp>
#include <list>
#include <memory>

#include "services/bus.hpp"

namespace hbirl::services {

class LcmBus final : public Bus {
 public:
  // Throws InputError("bus", ...) when LCM cannot start on this URL (for udpm:// on a
  // machine without a multicast route, the message says how to fix that).
  explicit LcmBus(const std::string& url);
  bool publish(const std::string& channel, const void* data, int size) override;
  SubscriptionId subscribe(const std::string& channel, RawHandler handler, int queue_capacity = 0) override;
  void unsubscribe(SubscriptionId id) override;
  int handle(int timeout_ms) override;
  std::string url() const override { return url_; }
  lcm::LCM& lcm() { return lcm_; }

 private:
  struct Subscriber {
    SubscriptionId id;
    RawHandler handler;
    lcm_subscription_t* lcm = nullptr;
  };
  std::string url_;
  lcm::LCM lcm_;
  std::list<Subscriber> subscribers_;  // stable addresses: LCM keeps pointers to them
  SubscriptionId next_id_ = 1;
};

}  // namespace hbirl::services
