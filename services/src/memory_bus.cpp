#include "services/memory_bus.hpp"

#include <algorithm>
#include <chrono>

namespace hbirl::services {

std::int64_t MemoryHub::published() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return published_;
}

void MemoryHub::set_loss(std::function<bool(const std::string&, const std::uint8_t*, int)> lose) {
  const std::lock_guard<std::mutex> lock(mutex_);
  lose_ = std::move(lose);
}

std::int64_t MemoryHub::dropped() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

MemoryBus::MemoryBus(std::shared_ptr<MemoryHub> hub) : hub_(std::move(hub)) {
  const std::lock_guard<std::mutex> lock(hub_->mutex_);
  hub_->endpoints_.push_back(this);
}

MemoryBus::~MemoryBus() { disconnect(); }

void MemoryBus::disconnect() {
  {
    const std::lock_guard<std::mutex> lock(hub_->mutex_);
    auto& e = hub_->endpoints_;
    e.erase(std::remove(e.begin(), e.end(), this), e.end());
  }
  const std::lock_guard<std::mutex> lock(mutex_);
  connected_ = false;
  for (auto& s : subscriptions_) s->queue.clear();
  ready_.notify_all();
}

bool MemoryBus::publish(const std::string& channel, const void* data, int size) {
  if (size < 0) return false;
  const std::int64_t now = wall_utime();
  const std::lock_guard<std::mutex> lock(hub_->mutex_);  // one order of delivery for everyone
  ++hub_->published_;
  if (hub_->lose_ && hub_->lose_(channel, static_cast<const std::uint8_t*>(data), size)) {
    ++hub_->dropped_;
    return true;  // sent, and lost on the way
  }
  for (MemoryBus* endpoint : hub_->endpoints_) {
    endpoint->deliver(channel, static_cast<const std::uint8_t*>(data), size, now);
  }
  return true;
}

void MemoryBus::deliver(const std::string& channel, const std::uint8_t* data, int size, std::int64_t now) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!connected_) return;
  bool any = false;
  for (auto& s : subscriptions_) {
    if (!s->channel->matches(channel)) continue;
    if (s->queue.size() >= s->capacity) {
      s->queue.pop_front();
      ++hub_->dropped_;  // the hub's mutex is held by publish()
    }
    s->queue.push_back(Queued{channel, std::vector<std::uint8_t>(data, data + size), now, order_++});
    any = true;
  }
  if (any) ready_.notify_all();
}

SubscriptionId MemoryBus::subscribe(const std::string& channel, RawHandler handler, int queue_capacity) {
  auto s = std::make_shared<Subscription>();
  s->pattern = channel;
  s->channel = std::make_unique<ChannelPattern>(channel);
  s->handler = std::move(handler);
  s->capacity = queue_capacity > 0 ? static_cast<size_t>(queue_capacity) : 30;
  const std::lock_guard<std::mutex> lock(mutex_);
  s->id = next_id_++;
  subscriptions_.push_back(s);
  return s->id;
}

void MemoryBus::unsubscribe(SubscriptionId id) {
  const std::lock_guard<std::mutex> lock(mutex_);
  std::erase_if(subscriptions_, [id](const auto& s) { return s->id == id; });
}

int MemoryBus::handle(int timeout_ms) {
  // Take everything queued so far, oldest first across subscriptions, then dispatch
  // without holding the lock (handlers publish).
  std::vector<std::pair<std::shared_ptr<Subscription>, Queued>> batch;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto any = [this] {
      return !connected_ ||
             std::any_of(subscriptions_.begin(), subscriptions_.end(), [](const auto& s) { return !s->queue.empty(); });
    };
    if (!any()) ready_.wait_for(lock, std::chrono::milliseconds(std::max(0, timeout_ms)), any);
    if (!connected_) return -1;
    for (auto& s : subscriptions_) {
      for (auto& q : s->queue) batch.emplace_back(s, std::move(q));
      s->queue.clear();
    }
  }
  std::sort(batch.begin(), batch.end(), [](const auto& a, const auto& b) { return a.second.order < b.second.order; });
  for (auto& [s, q] : batch)
    s->handler(Message{q.channel, q.data.data(), static_cast<int>(q.data.size()), q.recv_utime});
  return static_cast<int>(batch.size());
}

}  // namespace hbirl::services
