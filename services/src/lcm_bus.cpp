#include "services/lcm_bus.hpp"

#include <cerrno>

#include "learner/input_error.hpp"

namespace hbirl::services {

LcmBus::LcmBus(const std::string& url) : url_(url), lcm_(url) {
  if (!lcm_.good()) {
    std::string why = "LCM could not start on '" + (url.empty() ? std::string("the default udpm URL") : url) + "'";
    if (url.empty() || url.rfind("udpm://", 0) == 0) {
      why +=
          " (no multicast route? as root: ip route add 224.0.0.0/4 dev lo; or run inside "
          "services/launch.sh, which makes a private network namespace)";
    }
    throw InputError("bus", why);
  }
}

bool LcmBus::publish(const std::string& channel, const void* data, int size) {
  return lcm_.publish(channel, data, static_cast<unsigned int>(size)) == 0;
}

namespace {
// LCM's C callback. (LCM's C++ subscribe templates are not used: their dispatch casts
// trip UBSan's vptr check.)
extern "C" void on_lcm_message(const lcm_recv_buf_t* buffer, const char* channel, void* user) {
  const std::string name(channel);
  static_cast<const RawHandler*>(user)->operator()(Message{name, static_cast<const std::uint8_t*>(buffer->data),
                                                           static_cast<int>(buffer->data_size), buffer->recv_utime});
}
}  // namespace

SubscriptionId LcmBus::subscribe(const std::string& channel, RawHandler handler, int queue_capacity) {
  subscribers_.push_back(Subscriber{next_id_++, std::move(handler)});
  Subscriber& added = subscribers_.back();
  added.lcm = lcm_subscribe(lcm_.getUnderlyingLCM(), channel.c_str(), on_lcm_message, &added.handler);
  if (!added.lcm) {
    subscribers_.pop_back();
    throw InputError("channel", "LCM could not subscribe to '" + channel + "'");
  }
  if (queue_capacity > 0) lcm_subscription_set_queue_capacity(added.lcm, queue_capacity);
  return added.id;
}

void LcmBus::unsubscribe(SubscriptionId id) {
  for (auto it = subscribers_.begin(); it != subscribers_.end(); ++it) {
    if (it->id != id) continue;
    lcm_unsubscribe(lcm_.getUnderlyingLCM(), it->lcm);
    subscribers_.erase(it);
    return;
  }
}

int LcmBus::handle(int timeout_ms) {
  errno = 0;
  const int r = lcm_.handleTimeout(timeout_ms);
  if (r < 0) return errno == EINTR ? 0 : -1;  // a signal (e.g. SIGTERM) is not the end of the bus
  return r;                                   // LCM handles at most one message per call: 1, or 0 on timeout
}

}  // namespace hbirl::services
