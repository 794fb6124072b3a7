#include "services/log_bus.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>

#include "learner/input_error.hpp"

namespace hbirl::services {

namespace {

constexpr std::uint8_t kSync[4] = {0xED, 0xA1, 0xDA, 0x01};  // lcm-logger's sync word, big-endian
constexpr int kHeaderBytes = 28;  // sync, event number (8), time (8), channel length (4), data length (4)

std::int64_t be32(const std::uint8_t* p) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(p[0]) << 24 | static_cast<std::uint32_t>(p[1]) << 16 |
                                   static_cast<std::uint32_t>(p[2]) << 8 | p[3]);
}

std::int64_t be64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int k = 0; k < 8; ++k) v = v << 8 | p[k];
  return static_cast<std::int64_t>(v);
}

// The recording must be a regular file: a FIFO or a device would block or never end.
const std::string& regular_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw InputError("--log", "cannot read the LCM log '" + path + "': " + std::strerror(errno));
  struct stat st {};
  const bool regular = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
  ::close(fd);
  if (!regular) throw InputError("--log", "'" + path + "' is not a regular file (an lcm-logger recording)");
  return path;
}

std::int64_t file_size(std::FILE* file) {
  struct stat st {};
  return ::fstat(::fileno(file), &st) == 0 ? static_cast<std::int64_t>(st.st_size) : 0;
}

}  // namespace

LogBus::LogBus(const std::string& path, const std::string& out_path)
    : path_(path), in_(std::fopen(regular_file(path).c_str(), "rbe")) {
  if (!in_) throw InputError("--log", "cannot read the LCM log '" + path + "': " + std::strerror(errno));
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

// Reads the header at the reading position and goes back to it.
LogBus::Next LogBus::check_next(std::string& why, Header& header) {
  std::FILE* file = in_.get();
  const off_t at = ::ftello(file);
  std::uint8_t h[kHeaderBytes];
  const size_t got = std::fread(h, 1, kHeaderBytes, file);
  std::clearerr(file);
  ::fseeko(file, at, SEEK_SET);
  if (got < static_cast<size_t>(kHeaderBytes)) return Next::kEnd;
  const std::string where = "the event at byte " + std::to_string(at);
  if (std::memcmp(h, kSync, 4) != 0) {
    why = "no event starts at byte " + std::to_string(at) + " (no sync word)";
    return Next::kDamaged;
  }
  const std::int64_t channel = be32(h + 20), data = be32(h + 24);
  if (channel < 1 || channel > kMaxChannelBytes) {
    why = where + " states a channel name of " + std::to_string(channel) + " bytes (1 to " + std::to_string(kMaxChannelBytes) + " are read)";
    return Next::kDamaged;
  }
  if (data < 0 || data > kMaxEventBytes) {
    why = where + " states " + std::to_string(data) + " bytes of data (at most " + std::to_string(kMaxEventBytes >> 20) + " MB are read)";
    return Next::kDamaged;
  }
  // Cut short, or still being written.
  if (static_cast<std::int64_t>(at) + kHeaderBytes + channel + data > file_size(file)) return Next::kEnd;
  header = Header{be64(h + 12), channel, data};
  return Next::kEvent;
}

// Moves the reading position to the next sync word at or after it; when none is written
// yet, to where the search may go on from (the last three bytes could start one).
bool LogBus::skip_to_next_sync() {
  std::FILE* file = in_.get();
  off_t at = ::ftello(file);
  std::vector<std::uint8_t> chunk(1 << 16);
  for (;;) {
    const size_t got = std::fread(chunk.data(), 1, chunk.size(), file);
    std::clearerr(file);
    for (size_t k = 0; k + 4 <= got; ++k) {
      if (std::memcmp(chunk.data() + k, kSync, 4) == 0) {
        ::fseeko(file, at + static_cast<off_t>(k), SEEK_SET);
        return true;
      }
    }
    if (got < chunk.size()) {
      ::fseeko(file, at + static_cast<off_t>(got >= 3 ? got - 3 : 0), SEEK_SET);
      return false;
    }
    at += static_cast<off_t>(got - 3);
    ::fseeko(file, at, SEEK_SET);
  }
}

int LogBus::handle(int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(std::max(0, timeout_ms));
  std::FILE* file = in_.get();
  for (;;) {
    std::string why;
    Header header;
    Next next = lost_ ? (skip_to_next_sync() ? Next::kEvent : Next::kEnd) : Next::kEvent;
    lost_ = lost_ && next == Next::kEnd;
    const off_t at = ::ftello(file);
    if (next == Next::kEvent) next = check_next(why, header);
    if (next == Next::kDamaged) {
      if (!follow_) throw InputError("--log", "'" + path_ + "' is damaged: " + why);
      if (++damaged_ <= 20) std::fprintf(stderr, "hbirl: %s: %s: skipped to the next event\n", path_.c_str(), why.c_str());
      ::fseeko(file, at + 1, SEEK_SET);
      lost_ = true;
      continue;
    }
    if (next == Next::kEvent) {  // sound, and whole in the file: read it
      channel_.resize(static_cast<size_t>(header.channel_bytes));
      data_.resize(static_cast<size_t>(header.data_bytes));
      const bool whole = ::fseeko(file, at + kHeaderBytes, SEEK_SET) == 0 &&
                         std::fread(channel_.data(), 1, channel_.size(), file) == channel_.size() &&
                         std::fread(data_.data(), 1, data_.size(), file) == data_.size();
      if (!whole) next = Next::kEnd;
    }
    if (next == Next::kEnd) {
      if (!follow_) return -1;
      // The end, or an event the logger is still writing: read it again from its start
      // once more has been written (clearerr: glibc's end-of-file flag is sticky).
      std::clearerr(file);
      const bool truncated = file_size(file) < at;  // rewritten from the start (lcm-logger -f)
      ::fseeko(file, truncated ? 0 : at, SEEK_SET);
      if (truncated) lost_ = false;
      if (std::chrono::steady_clock::now() >= deadline) return 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    ++events_;
    last_utime_ = header.utime;
    int delivered = 0;
    for (const Subscription& s : subscriptions_) {
      if (!s.channel->matches(channel_)) continue;
      s.handler(Message{channel_, data_.data(), static_cast<int>(data_.size()), header.utime});
      ++delivered;
    }
    if (delivered > 0) return 1;
  }
}

}  // namespace hbirl::services
