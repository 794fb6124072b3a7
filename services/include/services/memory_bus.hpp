#pragma once
// In-process bus for unit tests: endpoints of one hub see each other's messages (and
// their own, as in LCM). Thread-safe: each endpoint may be handled from its own thread.
// Subscription queues have capacities and drop their oldest message when full, like
// LCM's. See bus.hpp.
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <vector>

#include "services/bus.hpp"

namespace hbirl::services {

class MemoryHub {
 public:
  std::int64_t published() const;
  std::int64_t dropped() const;  // by full subscription queues or the loss filter
  // Testing: a message for which `lose` returns true is lost on the way (as UDP may lose it).
  void set_loss(std::function<bool(const std::string& channel, const std::uint8_t* data, int size)> lose);

 private:
  friend class MemoryBus;
  mutable std::mutex mutex_;
  std::vector<class MemoryBus*> endpoints_;
  std::int64_t published_ = 0;
  std::int64_t dropped_ = 0;
  std::function<bool(const std::string&, const std::uint8_t*, int)> lose_;
};

class MemoryBus final : public Bus {
 public:
  explicit MemoryBus(std::shared_ptr<MemoryHub> hub);
  ~MemoryBus() override;
  MemoryBus(const MemoryBus&) = delete;
  MemoryBus& operator=(const MemoryBus&) = delete;

  bool publish(const std::string& channel, const void* data, int size) override;
  SubscriptionId subscribe(const std::string& channel, RawHandler handler, int queue_capacity = 0) override;
  void unsubscribe(SubscriptionId id) override;
  int handle(int timeout_ms) override;
  std::string url() const override { return "memory"; }
  // Stops delivering to this endpoint (a "killed" service): its queues are dropped.
  void disconnect();

 private:
  struct Queued {
    std::string channel;
    std::vector<std::uint8_t> data;
    std::int64_t recv_utime;
    std::uint64_t order;  // across this endpoint's subscriptions
  };
  struct Subscription {
    SubscriptionId id;
    std::string pattern;
    std::unique_ptr<ChannelPattern> channel;
    RawHandler handler;
    size_t capacity;
    std::deque<Queued> queue;
  };
  void deliver(const std::string& channel, const std::uint8_t* data, int size, std::int64_t now);

  std::shared_ptr<MemoryHub> hub_;
  std::mutex mutex_;  // guards subscriptions_' queues and connected_
  std::condition_variable ready_;
  std::vector<std::shared_ptr<Subscription>> subscriptions_;  // shared: handle() dispatches outside the lock
  std::uint64_t order_ = 0;
  SubscriptionId next_id_ = 1;
  bool connected_ = true;
};

}  // namespace hbirl::services
