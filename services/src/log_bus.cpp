#include "services/log_bus.hpp"

#include <sys/stat.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "learner/input_error.hpp"

namespace hbirl::services {

LogBus::LogBus(const std::string& path, const std::string& out_path) : path_(path), in_(path, "r") {
  if (!in_.good()) throw InputError("bus", "cannot read the LCM log '" + path + "'");
  if (!out_path.empty()) {
    out_ = std::make_unique<lcm::LogFile>(out_path, "w");
    if (!out_->good()) throw InputError("bus", "cannot write the LCM log '" + out_path + "'");
  }
}

bool LogBus::publish(const std::string& channel, const void* data, int size) {
  if (!out_) return true;
  lcm::LogEvent event;
  event.timestamp = last_utime_;  // the replayed clock
  event.channel = channel;
  event.datalen = size;
  event.data = const_cast<void*>(data);
  return out_->writeEvent(&event) == 0;
}

SubscriptionId LogBus::subscribe(const std::string& channel, RawHandler handler, int) {
  subscriptions_.push_back(Subscription{next_id_, std::make_unique<ChannelPattern>(channel), std::move(handler)});
  return next_id_++;
}

void LogBus::unsubscribe(SubscriptionId id) {
  std::erase_if(subscriptions_, [id](const Subscription& s) { return s.id == id; });
}

int LogBus::handle(int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(std::max(0, timeout_ms));
  for (;;) {
    std::FILE* file = in_.getFilePtr();
    const long at = follow_ ? std::ftell(file) : 0L;
    const lcm::LogEvent* event = in_.readNextEvent();
    if (!event) {
      if (!follow_) return -1;
      // The end, or an event the logger is still writing: read it again from its start
      // once more has been written (clearerr: glibc's end-of-file flag is sticky).
      std::clearerr(file);
      struct stat st {};
      const bool truncated = ::fstat(::fileno(file), &st) == 0 && st.st_size < at;  // rewritten from the start (lcm-logger -f)
      std::fseek(file, truncated ? 0L : at, SEEK_SET);
      if (std::chrono::steady_clock::now() >= deadline) return 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    ++events_;
    last_utime_ = event->timestamp;
    int delivered = 0;
    for (const Subscription& s : subscriptions_) {
      if (!s.channel->matches(event->channel)) continue;
      s.handler(Message{event->channel, static_cast<const std::uint8_t*>(event->data), event->datalen, event->timestamp});
      ++delivered;
    }
    if (delivered > 0) return 1;
  }
}

}  // namespace hbirl::services
