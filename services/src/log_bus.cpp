#include "services/log_bus.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
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
  // A large buffer: each event's header is read and the reader goes back to it, and events
  // nobody listens to are skipped by a seek, which stays inside the buffer.
  std::setvbuf(in_.get(), nullptr, _IOFBF, std::size_t{1} << 20);
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

// Reads the header at pos_. kEvent: the file is positioned after it; otherwise back at pos_.
LogBus::Next LogBus::check_next(std::string& why, Header& header) {
  std::FILE* file = in_.get();
  const auto back = [&] {
    std::clearerr(file);  // glibc's end-of-file flag is sticky
    ::fseeko(file, pos_, SEEK_SET);
  };
  std::uint8_t h[kHeaderBytes];
  if (std::fread(h, 1, kHeaderBytes, file) < static_cast<size_t>(kHeaderBytes)) {
    back();
    return Next::kEnd;
  }
  const std::string where = "the event at byte " + std::to_string(pos_);
  const std::int64_t channel = be32(h + 20), data = be32(h + 24);
  if (std::memcmp(h, kSync, 4) != 0) {
    why = "no event starts at byte " + std::to_string(pos_) + " (no sync word)";
  } else if (channel < 1 || channel > kMaxChannelBytes) {
    why = where + " states a channel name of " + std::to_string(channel) + " bytes (1 to " +
          std::to_string(kMaxChannelBytes) + " are read)";
  } else if (data < 0 || data > kMaxEventBytes) {
    why = where + " states " + std::to_string(data) + " bytes of data (at most " +
          std::to_string(kMaxEventBytes >> 20) + " MB are read)";
  }
  if (!why.empty()) {
    back();
    return Next::kDamaged;
  }
  // Cut short, or still being written (the file's size is asked for again only then).
  const std::int64_t end = pos_ + kHeaderBytes + channel + data;
  if (end > size_ && end > (size_ = file_size(file))) {
    back();
    return Next::kEnd;
  }
  header = Header{be64(h + 12), channel, data};
  return Next::kEvent;
}

// Moves pos_ (and the file) to the next sync word at or after pos_; when none is written
// yet, to where the search may go on from (the last three bytes could start one).
bool LogBus::skip_to_next_sync() {
  std::FILE* file = in_.get();
  ::fseeko(file, pos_, SEEK_SET);
  std::vector<std::uint8_t> chunk(1 << 16);
  for (;;) {
    const size_t got = std::fread(chunk.data(), 1, chunk.size(), file);
    std::clearerr(file);
    for (size_t k = 0; k + 4 <= got; ++k) {
      if (std::memcmp(chunk.data() + k, kSync, 4) == 0) {
        pos_ += static_cast<std::int64_t>(k);
        ::fseeko(file, pos_, SEEK_SET);
        return true;
      }
    }
    pos_ += static_cast<std::int64_t>(got >= 3 ? got - 3 : 0);
    ::fseeko(file, pos_, SEEK_SET);
    if (got < chunk.size()) return false;
  }
}

// The event's channel and, if someone listens to it, its data (the file positioned after
// its header); false if the file ends inside it.
bool LogBus::read_event(const Header& header, bool& wanted) {
  std::FILE* file = in_.get();
  channel_.resize(static_cast<size_t>(header.channel_bytes));
  if (std::fread(channel_.data(), 1, channel_.size(), file) != channel_.size()) return false;
  wanted = std::any_of(subscriptions_.begin(), subscriptions_.end(),
                       [this](const Subscription& s) { return s.channel->matches(channel_); });
  // Data nobody listens to is read through when it is small (a seek costs more), else skipped.
  if (wanted || header.data_bytes <= std::int64_t{1} << 20) {
    data_.resize(static_cast<size_t>(header.data_bytes));
    return std::fread(data_.data(), 1, data_.size(), file) == data_.size();
  }
  return ::fseeko(file, pos_ + kHeaderBytes + header.channel_bytes + header.data_bytes, SEEK_SET) == 0;
}

int LogBus::handle(int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(std::max(0, timeout_ms));
  std::FILE* file = in_.get();
  for (;;) {
    std::string why;
    Header header;
    if (lost_) lost_ = !skip_to_next_sync();
    Next next = lost_ ? Next::kEnd : check_next(why, header);
    if (next == Next::kDamaged) {
      if (!follow_) throw InputError("--log", "'" + path_ + "' is damaged: " + why);
      if (++damaged_ <= 20)
        std::fprintf(stderr, "hbirl: %s: %s: skipped to the next event\n", path_.c_str(), why.c_str());
      ++pos_;
      lost_ = true;
      continue;
    }
    bool wanted = false;
    if (next == Next::kEvent && !read_event(header, wanted)) {
      std::clearerr(file);
      ::fseeko(file, pos_, SEEK_SET);
      next = Next::kEnd;
    }
    if (next == Next::kEnd) {
      if (!follow_) return -1;
      // The end, or an event the logger is still writing: read it again from its start
      // once more has been written.
      if (file_size(file) < pos_) {  // rewritten from the start (lcm-logger -f)
        pos_ = 0;
        lost_ = false;
        ::fseeko(file, 0, SEEK_SET);
      }
      size_ = 0;
      if (std::chrono::steady_clock::now() >= deadline) return 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }
    pos_ += kHeaderBytes + header.channel_bytes + header.data_bytes;
    ++events_;
    last_utime_ = header.utime;
    if (!wanted) continue;
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
