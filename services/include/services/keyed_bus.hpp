#pragma once
// Message authentication with a run key (docs/RELIABILITY.md). LCM, like ROS 1, has no
// authentication: anyone on the multicast group can publish on any channel. With a key,
// every message carries a tag -- HMAC-SHA-512-256 (libsodium's crypto_auth) over the run's
// identity, its channel and its bytes -- and a message without a valid tag is counted and
// dropped before it is decoded; one signed for another run is counted and dropped too, so
// a key shared by many runs (and machines) does not let one run's messages into another.
// It protects integrity and origin (only holders of the key publish), not
// confidentiality: the bytes still travel in the clear.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "services/bus.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

// A run's identity: 8 random bytes, never 0, chosen for every run (services/launch.sh).
using RunId = std::uint64_t;
std::string run_id_text(RunId run);  // 16 hexadecimal digits

// 32 random bytes shared by the processes that may publish, and the run they publish for.
// On disk: 64 hexadecimal digits and a newline, then -- in a run's key file -- a line
// "run " and the run's 16 hexadecimal digits; the file is readable and writable by its
// owner only (mode 0600), like an SSH private key. A key file without a run line
// (hbirl keygen FILE) may serve many runs: services/launch.sh writes each run its own key
// file, the same key with a fresh run (OUT/run.key).
class RunKey {
 public:
  static constexpr int kBytes = 32;
  static RunKey generate();  // a fresh key, for no run yet
  // Throws InputError("--key", ...) when the file is missing, not a regular file,
  // malformed, or readable or writable by anyone but its owner.
  static RunKey read(const std::string& path);
  // Creates `path` with mode 0600; refuses to overwrite (InputError("--key", ...)).
  void write(const std::string& path) const;
  // The same key for a fresh, random run.
  RunKey for_new_run() const;
  const std::array<std::uint8_t, kBytes>& bytes() const { return bytes_; }
  std::optional<RunId> run() const { return run_; }

 private:
  std::array<std::uint8_t, kBytes> bytes_{};
  std::optional<RunId> run_;
};

// Whether `data` (a whole message on `channel`, trailer included) is signed with `key`;
// if so, *run is the run it was signed for.
bool signed_with(const RunKey& key, const std::string& channel, const std::uint8_t* data, int size, RunId* run);

// Which runs' messages a keyed bus believes, when its key file names no run.
enum class KeyUse {
  kService,  // a service of one run: its key file must name the run
  kWorker,   // a sampler worker: any run of the key; each answer signed for its request's run (sign_for_run)
  kReader,   // a recording's reader or a dashboard: the run of the first message signed with the key
};

// A bus whose messages are signed on the way out and checked on the way in. Messages
// without a valid tag reach no handler; each is counted in `counters` as bad. A key that
// names a run believes only that run's messages; otherwise `use` says which (KeyUse).
// Messages of another run are counted as bad and in counters.other_run.
class KeyedBus final : public Bus {
 public:
  KeyedBus(std::unique_ptr<Bus> inner, const RunKey& key, Counters& counters, KeyUse use = KeyUse::kService);
  bool publish(const std::string& channel, const void* data, int size) override;
  SubscriptionId subscribe(const std::string& channel, RawHandler handler, int queue_capacity = 0) override;
  void unsubscribe(SubscriptionId id) override { inner_->unsubscribe(id); }
  int handle(int timeout_ms) override { return inner_->handle(timeout_ms); }
  std::string url() const override { return inner_->url(); }
  void sign_for_run(RunId run) override;
  Bus& inner() { return *inner_; }
  std::int64_t rejected() const { return rejected_; }
  // The run whose messages this bus believes (0: not known yet, or any: KeyUse::kWorker).
  RunId run() const { return run_; }

 private:
  bool believes(RunId run);
  std::unique_ptr<Bus> inner_;
  RunKey key_;
  Counters& counters_;
  KeyUse use_;
  RunId run_ = 0;      // believed, and signed for
  RunId signing_ = 0;  // KeyUse::kWorker: the run signed for
  std::int64_t rejected_ = 0;
};

// A recording's key, checked before it is read: without `key_file`, a recording whose
// messages are signed is refused ("give it"); with it, one none of whose first signed
// messages is signed with that key is refused as the wrong key, and one with no signed
// message as not signed. InputError("--key", ...) in one line.
void check_recording_key(const std::string& log_path, const std::string& key_file);

// `bus` signed and checked with the key in `key_file`, or -- with no key file -- as it is,
// after saying once on stderr (unless `use` is kReader) that the bus is unauthenticated;
// counters.authenticated, which every heartbeat reports, says which. Throws
// InputError("--key", ...) for a service's key file that names no run (KeyUse::kService).
std::unique_ptr<Bus> with_key(std::unique_ptr<Bus> bus, const std::string& key_file, Counters& counters,
                              KeyUse use = KeyUse::kService);

}  // namespace hbirl::services
