#pragma once
// Bus on an lcm-logger file: handle() delivers the recorded events one by one, in order,
// as fast as they are handled, so a replay is deterministic. See bus.hpp.
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <vector>

#include "services/bus.hpp"

namespace hbirl::services {

class LogBus final : public Bus {
 public:
  // Throws InputError("bus", ...) if the log cannot be read (or `out_path` written).
  explicit LogBus(const std::string& path, const std::string& out_path = "");
  // Follow mode (the dashboard on a run being recorded): at the end of the log, handle()
  // waits up to its timeout for more to be written (returning 0, never -1); a log
  // rewritten from the start is read again from its start.
  void follow(bool on) { follow_ = on; }
  // Writes to the output log when there is one; otherwise drops the message.
  bool publish(const std::string& channel, const void* data, int size) override;
  SubscriptionId subscribe(const std::string& channel, RawHandler handler, int queue_capacity = 0) override;
  void unsubscribe(SubscriptionId id) override;
  // Delivers the next recorded event to its subscribers (events nobody subscribes to are
  // skipped); -1 at the end of the log (unless following it).
  int handle(int timeout_ms) override;
  std::string url() const override { return "log:" + path_; }
  std::int64_t events_read() const { return events_; }

 private:
  struct Subscription {
    SubscriptionId id;
    std::unique_ptr<ChannelPattern> channel;
    RawHandler handler;
  };
  std::string path_;
  lcm::LogFile in_;
  std::unique_ptr<lcm::LogFile> out_;
  std::vector<Subscription> subscriptions_;
  SubscriptionId next_id_ = 1;
  std::int64_t events_ = 0;
  std::int64_t last_utime_ = 0;
  bool follow_ = false;
};

}  // namespace hbirl::services
