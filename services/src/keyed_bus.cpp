// Message authentication with a run key (keyed_bus.hpp; docs/RELIABILITY.md).
#include "services/keyed_bus.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <cstring>
#include <vector>

#include "learner/input_error.hpp"

namespace hbirl::services {

namespace {

void init_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
}

// HMAC-SHA-512-256 over the channel's name, a zero byte, and the message: a signed message
// moved to another channel fails (the type fingerprints would mostly catch it anyway).
std::array<std::uint8_t, kTagBytes> tag_of(const RunKey& key, const std::string& channel, const void* data, int size) {
  static_assert(crypto_auth_hmacsha512256_BYTES == kTagBytes, "tag size");
  static_assert(crypto_auth_hmacsha512256_KEYBYTES == RunKey::kBytes, "key size");
  crypto_auth_hmacsha512256_state state;
  crypto_auth_hmacsha512256_init(&state, key.bytes().data(), key.bytes().size());
  const std::uint8_t zero = 0;
  crypto_auth_hmacsha512256_update(&state, reinterpret_cast<const unsigned char*>(channel.data()), channel.size());
  crypto_auth_hmacsha512256_update(&state, &zero, 1);
  crypto_auth_hmacsha512256_update(&state, static_cast<const unsigned char*>(data), static_cast<unsigned long long>(size));
  std::array<std::uint8_t, kTagBytes> tag{};
  crypto_auth_hmacsha512256_final(&state, tag.data());
  return tag;
}

}  // namespace

RunKey RunKey::generate() {
  init_sodium();
  RunKey key;
  randombytes_buf(key.bytes_.data(), key.bytes_.size());
  return key;
}

RunKey RunKey::read(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) throw InputError("--key", "cannot open '" + path + "': " + std::strerror(errno));
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError("--key", "'" + path + "' is not a regular file");
  }
  if ((st.st_mode & 077) != 0) {
    ::close(fd);
    throw InputError("--key", "'" + path + "' may be read or written by others (mode " +
                                  std::to_string((st.st_mode >> 6) & 7) + std::to_string((st.st_mode >> 3) & 7) +
                                  std::to_string(st.st_mode & 7) + "): chmod 600 it");
  }
  char text[2 * kBytes + 2] = {0};
  const ssize_t n = ::read(fd, text, sizeof text);
  ::close(fd);
  const bool newline = n == 2 * kBytes + 1 && text[2 * kBytes] == '\n';
  if (n != 2 * kBytes && !newline) throw InputError("--key", "'" + path + "' must hold 64 hexadecimal digits (hbirl keygen makes one)");
  RunKey key;
  size_t used = 0;
  if (sodium_hex2bin(key.bytes_.data(), key.bytes_.size(), text, 2 * kBytes, nullptr, &used, nullptr) != 0 ||
      used != key.bytes_.size()) {
    throw InputError("--key", "'" + path + "' must hold 64 hexadecimal digits (hbirl keygen makes one)");
  }
  sodium_memzero(text, sizeof text);
  return key;
}

void RunKey::write(const std::string& path) const {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) throw InputError("--key", "cannot create '" + path + "': " + std::strerror(errno));
  char text[2 * kBytes + 1];
  sodium_bin2hex(text, sizeof text, bytes_.data(), bytes_.size());
  text[2 * kBytes] = '\n';
  const bool ok = ::write(fd, text, sizeof text) == static_cast<ssize_t>(sizeof text) && ::fsync(fd) == 0;
  sodium_memzero(text, sizeof text);
  if (::close(fd) != 0 || !ok) throw InputError("--key", "could not write '" + path + "'");
}

KeyedBus::KeyedBus(std::unique_ptr<Bus> inner, const RunKey& key, Counters& counters)
    : inner_(std::move(inner)), key_(key), counters_(counters) {
  init_sodium();
  counters_.authenticated = true;
}

bool KeyedBus::publish(const std::string& channel, const void* data, int size) {
  std::vector<std::uint8_t> signed_bytes(static_cast<size_t>(size) + kTrailerBytes);
  if (size > 0) std::memcpy(signed_bytes.data(), data, static_cast<size_t>(size));
  const auto tag = tag_of(key_, channel, data, size);
  std::memcpy(signed_bytes.data() + size, tag.data(), kTagBytes);
  std::memcpy(signed_bytes.data() + size + kTagBytes, kTrailerMarker, 4);
  return inner_->publish(channel, signed_bytes.data(), static_cast<int>(signed_bytes.size()));
}

SubscriptionId KeyedBus::subscribe(const std::string& channel, RawHandler handler, int queue_capacity) {
  return inner_->subscribe(
      channel,
      [this, handler = std::move(handler)](const Message& m) {
        const int body = m.size - kTrailerBytes;
        const bool valid = has_trailer(m.data, m.size) &&
                           sodium_memcmp(tag_of(key_, m.channel, m.data, body).data(), m.data + body, kTagBytes) == 0;
        if (!valid) {
          ++rejected_;
          counters_.bad(m.channel, "not signed with this run's key: dropped unread");
          return;
        }
        handler(Message{m.channel, m.data, body, m.recv_utime});
      },
      queue_capacity);
}

void require_key_if_signed(const std::string& log_path, const std::string& key_file) {
  if (!key_file.empty()) return;
  lcm::LogFile log(log_path, "r");
  if (!log.good()) return;  // the reader says why
  // The first of hbirl's messages decides (LCM's own, e.g. LCM_SELF_TEST, are never signed).
  for (int k = 0; k < 1000; ++k) {
    const lcm::LogEvent* event = log.readNextEvent();
    if (!event) return;
    if (event->channel.rfind("LCM_", 0) == 0) continue;
    if (has_trailer(static_cast<const std::uint8_t*>(event->data), event->datalen)) {
      throw InputError("--key", "the messages in '" + log_path + "' are signed with a run key: give it (launch.sh wrote OUT/run.key)");
    }
    return;
  }
}

std::unique_ptr<Bus> with_key(std::unique_ptr<Bus> bus, const std::string& key_file, Counters& counters, bool live) {
  if (key_file.empty()) {
    counters.authenticated = false;
    if (live)
      counters.note("the bus is unauthenticated (no --key): any process on the multicast group can publish to this run "
                  "(docs/RELIABILITY.md)");
    return bus;
  }
  return std::make_unique<KeyedBus>(std::move(bus), RunKey::read(key_file), counters);
}

}  // namespace hbirl::services
