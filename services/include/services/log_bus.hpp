#pragma once
// Bus on an lcm-logger file: handle() delivers the recorded events one by one, in order,
// as fast as they are handled, so a replay is deterministic. See bus.hpp.
//
// A recording is input like any other, so its events are read here, each header checked
// before anything is allocated for it, rather than by LCM's reader: that one allocates
// whatever data length an event states (a length of 2^31 - 1 made it write through a
// failed allocation: SIGSEGV in every reader, from a 54-byte file), and silently drops an
// event followed by anything but another event. lcm-logger's event (LCM's file format) is
// a sync word, the event number, the time, the channel's and the data's lengths (all
// big-endian), then the channel and the data. An event whose channel is empty or longer
// than kMaxChannelBytes, whose data is longer than kMaxEventBytes, or that does not start
// with the sync word is damage: reading a finished recording throws InputError("--log",
// ...) naming the byte; following one (the dashboard) says so and reads on from the next
// sync word. An event the file ends inside is the end of the recording (one cut short:
// the reader of a run then finds what is missing). Writing (`out_path`) is LCM's.
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <vector>

#include "services/bus.hpp"

namespace hbirl::services {

class LogBus final : public Bus {
 public:
  static constexpr std::int64_t kMaxChannelBytes = 255;  // LCM's own limit is 63
  static constexpr std::int64_t kMaxEventBytes = std::int64_t{256} << 20;
  // Throws InputError("--log", ...) if the log is not a regular file or cannot be read,
  // InputError("bus", ...) if `out_path` cannot be written.
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
  // The time lcm-logger recorded for the last event read (microseconds).
  std::int64_t last_utime() const { return last_utime_; }
  // Following: damaged events skipped so far.
  std::int64_t damaged() const { return damaged_; }

 private:
  struct Subscription {
    SubscriptionId id;
    std::unique_ptr<ChannelPattern> channel;
    RawHandler handler;
  };
  struct CloseFile {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::string path_;
  std::unique_ptr<std::FILE, CloseFile> in_;
  std::string channel_;  // the event being delivered
  std::vector<std::uint8_t> data_;
  std::unique_ptr<lcm::LogFile> out_;
  std::vector<Subscription> subscriptions_;
  SubscriptionId next_id_ = 1;
  // The event at the reading position: whether its header can be read whole and is sound
  // (then its lengths and time), and the event within the file.
  enum class Next { kEvent, kEnd, kDamaged };
  struct Header {
    std::int64_t utime = 0, channel_bytes = 0, data_bytes = 0;
  };
  Next check_next(std::string& why, Header& header);
  bool skip_to_next_sync();  // from pos_; false: none in what is written yet
  bool read_event(const Header& header, bool& wanted);
  std::int64_t pos_ = 0;   // the reading position: the start of the next event
  std::int64_t size_ = 0;  // the file's size when last asked
  std::int64_t events_ = 0;
  std::int64_t damaged_ = 0;
  bool lost_ = false;  // following past damage: looking for the next sync word
  std::int64_t last_utime_ = 0;
  bool follow_ = false;
};

}  // namespace hbirl::services
