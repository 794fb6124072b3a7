#pragma once
// Message authentication with a run key (docs/RELIABILITY.md). LCM, like ROS 1, has no
// authentication: anyone on the multicast group can publish on any channel. With a key,
// every message carries a tag -- HMAC-SHA-512-256 (libsodium's crypto_auth) over its
// channel and bytes -- and a message without a valid tag is counted and dropped before
// it is decoded. It protects integrity and origin (only holders of the key publish), not
// confidentiality: the bytes still travel in the clear.
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "services/bus.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

// 32 random bytes, shared by the processes of one run (services/launch.sh makes a fresh
// one per run). On disk: 64 hexadecimal digits and a newline, in a file only its owner
// may read or write (mode 0600), like an SSH private key.
class RunKey {
 public:
  static constexpr int kBytes = 32;
  static RunKey generate();
  // Throws InputError("--key", ...) when the file is missing, malformed, or readable or
  // writable by anyone but its owner.
  static RunKey read(const std::string& path);
  // Creates `path` with mode 0600; refuses to overwrite (InputError("--key", ...)).
  void write(const std::string& path) const;
  const std::array<std::uint8_t, kBytes>& bytes() const { return bytes_; }

 private:
  std::array<std::uint8_t, kBytes> bytes_{};
};

// What a signed message carries after its LCM encoding (the tag and a marker) and
// has_trailer(): typed.hpp.

// A bus whose messages are signed on the way out and checked on the way in. Messages
// without a valid tag reach no handler; each is counted in `counters` as bad.
class KeyedBus final : public Bus {
 public:
  KeyedBus(std::unique_ptr<Bus> inner, const RunKey& key, Counters& counters);
  bool publish(const std::string& channel, const void* data, int size) override;
  SubscriptionId subscribe(const std::string& channel, RawHandler handler, int queue_capacity = 0) override;
  void unsubscribe(SubscriptionId id) override { inner_->unsubscribe(id); }
  int handle(int timeout_ms) override { return inner_->handle(timeout_ms); }
  std::string url() const override { return inner_->url(); }
  Bus& inner() { return *inner_; }
  std::int64_t rejected() const { return rejected_; }

 private:
  std::unique_ptr<Bus> inner_;
  RunKey key_;
  Counters& counters_;
  std::int64_t rejected_ = 0;
};

// A recording to be read without a key whose first hbirl message is signed: throws
// InputError("--key", ...) saying so (instead of every message failing to decode).
void require_key_if_signed(const std::string& log_path, const std::string& key_file);

// `bus` signed and checked with the key in `key_file`, or -- with no key file -- as it is,
// after saying once on stderr (for a `live` bus) that the bus is unauthenticated;
// counters.authenticated, which every heartbeat reports, says which.
std::unique_ptr<Bus> with_key(std::unique_ptr<Bus> bus, const std::string& key_file, Counters& counters, bool live = true);

}  // namespace hbirl::services
