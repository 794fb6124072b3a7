#pragma once
// The bus every hbirl service talks through (docs/services.md "Services and channels"), one abstract bus
// interface: raw messages on named channels, with three implementations behind one
// interface so that a service's code is the same live, in a replay and in a unit test:
//   LcmBus     LCM itself: udpm:// (live, several machines), memq:// (in-process), and
//              LCM's own file:// log provider (replay at recorded speed);
//   LogBus     an lcm-logger file read event by event, as fast as the service handles
//              them: deterministic replay;
//   MemoryBus  endpoints of an in-process hub, for unit tests (thread-safe).
// A service calls handle() from one thread only; handlers run inside handle().
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace hbirl::services {

// One message as delivered. `recv_utime` is when it arrived (for a log: when it was
// recorded); services act on the message's own utime, never on this.
// `run`: the run it was signed for, when a keyed bus checked it (keyed_bus.hpp); else 0.
struct Message {
  const std::string& channel;
  const std::uint8_t* data;
  int size;
  std::int64_t recv_utime;
  std::uint64_t run = 0;
};
using RawHandler = std::function<void(const Message&)>;

// The wall clock in microseconds: for heartbeats, arrival stamps and display only, never
// for results (services act on the messages' utime).
std::int64_t wall_utime();
using SubscriptionId = std::uint64_t;

class Bus {
 public:
  virtual ~Bus() = default;
  // Sends raw bytes; false if the bus could not (the caller counts it).
  virtual bool publish(const std::string& channel, const void* data, int size) = 0;
  // `channel` is a regular expression matched against the whole channel name (LCM's
  // rule). `queue_capacity`: messages kept for this subscription between handle() calls
  // before the oldest are dropped; choose it on purpose (0: the bus's default, 30 in LCM).
  virtual SubscriptionId subscribe(const std::string& channel, RawHandler handler, int queue_capacity = 0) = 0;
  // Ends a subscription: its handler is not called again (what is queued for it is
  // dropped). Call it from the thread that calls handle() (or while none does), never
  // from inside a handler. Unknown ids are ignored.
  virtual void unsubscribe(SubscriptionId id) = 0;
  // Dispatches waiting messages, waiting up to timeout_ms for the first. Returns how many
  // were dispatched (0: timed out), or -1 when the bus has ended (a log at its end) or
  // failed.
  virtual int handle(int timeout_ms) = 0;
  virtual std::string url() const = 0;
  // A bus that signs for a run and serves any run of its key (a sampler worker started
  // with a key file that names none; keyed_bus.hpp) signs what is published from now on
  // for `run`: the run of the request being answered. Other buses ignore it.
  virtual void sign_for_run(std::uint64_t /*run*/) {}
};

// Subscriptions that end with their owner: a service holds one as its last member (so it
// is destroyed first), and no handler ever runs into a destroyed service. The buses must
// outlive it, and it ends on the thread that handles the bus (as unsubscribe() says).
class Subscriptions {
 public:
  Subscriptions() = default;
  ~Subscriptions() { clear(); }
  Subscriptions(const Subscriptions&) = delete;
  Subscriptions& operator=(const Subscriptions&) = delete;
  void add(Bus& bus, SubscriptionId id) { held_.emplace_back(&bus, id); }
  void clear() {
    for (auto& [bus, id] : held_) bus->unsubscribe(id);
    held_.clear();
  }

 private:
  std::vector<std::pair<Bus*, SubscriptionId>> held_;
};

// A subscription's channel pattern: a POSIX extended regular expression matched against
// the whole channel name, as LCM does. Throws InputError("channel", ...) if it does not
// compile.
class ChannelPattern {
 public:
  explicit ChannelPattern(const std::string& pattern);
  ~ChannelPattern();
  ChannelPattern(const ChannelPattern&) = delete;
  ChannelPattern& operator=(const ChannelPattern&) = delete;
  bool matches(const std::string& channel) const;

 private:
  struct Compiled;
  std::unique_ptr<Compiled> compiled_;
};

// "log:PATH" opens a LogBus on an lcm-logger file (publishing is then a no-op unless
// "log:PATH?out=OUT" names a log to write to); anything else is an LCM URL ("" is LCM's
// default, udpm://239.255.76.67:7667). Throws InputError("bus", ...) if it cannot open.
std::unique_ptr<Bus> open_bus(const std::string& url);

}  // namespace hbirl::services
