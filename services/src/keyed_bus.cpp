// Message authentication with a run key (keyed_bus.hpp; docs/RELIABILITY.md).
#include "services/keyed_bus.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <vector>

#include "learner/input_error.hpp"
#include "services/log_bus.hpp"

namespace hbirl::services {

namespace {

void init_sodium() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
}

void put_run(RunId run, std::uint8_t* out) {
  for (int k = 0; k < kRunBytes; ++k) out[k] = static_cast<std::uint8_t>(run >> (8 * (kRunBytes - 1 - k)));
}

RunId get_run(const std::uint8_t* in) {
  RunId run = 0;
  for (int k = 0; k < kRunBytes; ++k) run = run << 8 | in[k];
  return run;
}

// HMAC-SHA-512-256 over the run, the channel's name, a zero byte, and the message: a signed
// message moved to another channel or presented as another run's fails.
std::array<std::uint8_t, kTagBytes> tag_of(const RunKey& key, RunId run, const std::string& channel, const void* data,
                                           int size) {
  static_assert(crypto_auth_hmacsha512256_BYTES == kTagBytes, "tag size");
  static_assert(crypto_auth_hmacsha512256_KEYBYTES == RunKey::kBytes, "key size");
  crypto_auth_hmacsha512256_state state;
  crypto_auth_hmacsha512256_init(&state, key.bytes().data(), key.bytes().size());
  std::uint8_t run_bytes[kRunBytes];
  put_run(run, run_bytes);
  const std::uint8_t zero = 0;
  crypto_auth_hmacsha512256_update(&state, run_bytes, kRunBytes);
  crypto_auth_hmacsha512256_update(&state, reinterpret_cast<const unsigned char*>(channel.data()), channel.size());
  crypto_auth_hmacsha512256_update(&state, &zero, 1);
  crypto_auth_hmacsha512256_update(&state, static_cast<const unsigned char*>(data),
                                   static_cast<unsigned long long>(size));
  std::array<std::uint8_t, kTagBytes> tag{};
  crypto_auth_hmacsha512256_final(&state, tag.data());
  return tag;
}

bool parse_hex(const char* text, size_t digits, std::uint8_t* out, size_t bytes) {
  size_t used = 0;
  return sodium_hex2bin(out, bytes, text, digits, nullptr, &used, nullptr) == 0 && used == bytes;
}

const char* const kKeyFormat =
    "must hold 64 hexadecimal digits, and for one run a second line 'run' and 16 more (hbirl keygen makes one)";

}  // namespace

std::string run_id_text(RunId run) {
  std::uint8_t bytes[kRunBytes];
  put_run(run, bytes);
  char text[2 * kRunBytes + 1];
  sodium_bin2hex(text, sizeof text, bytes, kRunBytes);
  return text;
}

RunKey RunKey::generate() {
  init_sodium();
  RunKey key;
  randombytes_buf(key.bytes_.data(), key.bytes_.size());
  return key;
}

RunKey RunKey::for_new_run() const {
  init_sodium();
  RunKey key = *this;
  RunId run = 0;
  while (run == 0) randombytes_buf(&run, sizeof run);
  key.run_ = run;
  return key;
}

RunKey RunKey::read(const std::string& path) {
  // O_NONBLOCK: opening a FIFO must not wait for a writer (it is refused below).
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
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
  // The key's line, then optionally "run " and the run's digits: at most 87 bytes.
  constexpr size_t kKeyDigits = 2 * kBytes, kRunDigits = 2 * kRunBytes;
  char text[kKeyDigits + 1 + 4 + kRunDigits + 2] = {0};
  const ssize_t n = ::read(fd, text, sizeof text);
  ::close(fd);
  RunKey key;
  const auto malformed = [&]() -> InputError {
    sodium_memzero(text, sizeof text);
    return InputError("--key", "'" + path + "' " + kKeyFormat);
  };
  if (n < static_cast<ssize_t>(kKeyDigits) || !parse_hex(text, kKeyDigits, key.bytes_.data(), key.bytes_.size()))
    throw malformed();
  std::string rest(text + kKeyDigits, static_cast<size_t>(n) - kKeyDigits);
  sodium_memzero(text, sizeof text);
  if (!rest.empty() && rest.back() == '\n') rest.pop_back();  // the file's last newline
  if (!rest.empty()) {
    if (rest.size() != 1 + 4 + kRunDigits || rest.compare(0, 5, "\nrun ") != 0) throw malformed();
    std::uint8_t run[kRunBytes];
    if (!parse_hex(rest.data() + 5, kRunDigits, run, kRunBytes) || get_run(run) == 0) throw malformed();
    key.run_ = get_run(run);
  }
  return key;
}

void RunKey::write(const std::string& path) const {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) throw InputError("--key", "cannot create '" + path + "': " + std::strerror(errno));
  char hex[2 * kBytes + 1];
  sodium_bin2hex(hex, sizeof hex, bytes_.data(), bytes_.size());
  std::string text = std::string(hex, 2 * kBytes) + "\n";
  sodium_memzero(hex, sizeof hex);
  if (run_) text += "run " + run_id_text(*run_) + "\n";
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) && ::fsync(fd) == 0;
  sodium_memzero(text.data(), text.size());
  if (::close(fd) != 0 || !ok) throw InputError("--key", "could not write '" + path + "'");
}

bool signed_with(const RunKey& key, const std::string& channel, const std::uint8_t* data, int size, RunId* run) {
  if (!has_trailer(data, size)) return false;
  const int body = size - kTrailerBytes;
  const RunId claimed = get_run(data + body + kTagBytes);
  if (sodium_memcmp(tag_of(key, claimed, channel, data, body).data(), data + body, kTagBytes) != 0) return false;
  if (run) *run = claimed;
  return true;
}

KeyedBus::KeyedBus(std::unique_ptr<Bus> inner, const RunKey& key, Counters& counters, KeyUse use)
    : inner_(std::move(inner)), key_(key), counters_(counters), use_(use), run_(key.run().value_or(0)) {
  init_sodium();
  counters_.authenticated = true;
}

void KeyedBus::sign_for_run(RunId run) {
  if (use_ == KeyUse::kWorker && !key_.run()) signing_ = run;
}

bool KeyedBus::publish(const std::string& channel, const void* data, int size) {
  const RunId run = run_ != 0 ? run_ : signing_;
  // A worker of every run that has heard from none yet has no run to sign for: what it
  // would send (a heartbeat) could only be counted as another run's by every optimiser.
  if (run == 0 && use_ == KeyUse::kWorker) return true;
  std::vector<std::uint8_t> signed_bytes(static_cast<size_t>(size) + kTrailerBytes);
  if (size > 0) std::memcpy(signed_bytes.data(), data, static_cast<size_t>(size));
  const auto tag = tag_of(key_, run, channel, data, size);
  std::memcpy(signed_bytes.data() + size, tag.data(), kTagBytes);
  put_run(run, signed_bytes.data() + size + kTagBytes);
  std::memcpy(signed_bytes.data() + size + kTagBytes + kRunBytes, kTrailerMarker, 4);
  return inner_->publish(channel, signed_bytes.data(), static_cast<int>(signed_bytes.size()));
}

// The run a validly signed message was signed for is this bus's run: the key's, or the
// first one seen (a reader), or any (a worker).
bool KeyedBus::believes(RunId run) {
  if (key_.run() || use_ == KeyUse::kService) return run == run_;
  if (use_ == KeyUse::kWorker) {
    if (signing_ == 0) signing_ = run;  // its first run: heartbeats go there until a request says otherwise
    return true;
  }
  if (run_ == 0) run_ = run;
  return run == run_;
}

SubscriptionId KeyedBus::subscribe(const std::string& channel, RawHandler handler, int queue_capacity) {
  return inner_->subscribe(
      channel,
      [this, handler = std::move(handler)](const Message& m) {
        RunId run = 0;
        if (!signed_with(key_, m.channel, m.data, m.size, &run)) {
          ++rejected_;
          counters_.bad(m.channel, has_old_trailer(m.data, m.size)
                                       ? "signed in the format before run identities (hbk1): dropped unread"
                                       : "not signed with this run's key: dropped unread");
          return;
        }
        if (!believes(run)) {  // said once; a replay of a whole run would say it thousands of times
          ++rejected_;
          const std::string why = "signed for another run (" + run_id_text(run) + ", this one is " + run_id_text(run_) +
                                  "): dropped unread, as every other run's message will be";
          // (A reader whose key file names no run refuses the recording for it: no line each.)
          if (++counters_.other_run == 1 && (use_ != KeyUse::kReader || key_.run())) {
            counters_.bad(m.channel, why);
          } else {
            ++counters_.bad_messages;
            counters_.last_problem = m.channel + ": " + why;
          }
          return;
        }
        handler(Message{m.channel, m.data, m.size - kTrailerBytes, m.recv_utime, run});
      },
      queue_capacity);
}

void check_recording_key(const std::string& log_path, const std::string& key_file) {
  const std::optional<RunKey> key = key_file.empty() ? std::nullopt : std::optional<RunKey>(RunKey::read(key_file));
  LogBus log(log_path);
  // hbirl's messages decide (LCM's own, e.g. LCM_SELF_TEST, are never signed): without a
  // key, the first one says whether they are signed; with one, the recording is read until a
  // message signed with it (for its run, when the key file names one) is found -- to the
  // end if none is: messages a forger recorded first cannot make the key "wrong".
  int hbirl_messages = 0, signed_messages = 0, old_format = 0, with_key = 0;
  bool found = false;
  RunId recorded_run = 0;  // the run of the first message signed with the key
  const SubscriptionId all = log.subscribe(".*", [&](const Message& m) {
    if (m.channel.rfind("LCM_", 0) == 0) return;
    ++hbirl_messages;
    if (has_old_trailer(m.data, m.size)) ++old_format;
    if (!has_trailer(m.data, m.size)) return;
    ++signed_messages;
    RunId run = 0;
    if (!key || !signed_with(*key, m.channel, m.data, m.size, &run)) return;
    ++with_key;
    if (recorded_run == 0) recorded_run = run;
    found = found || !key->run() || run == *key->run();
  });
  while (!found && (key || hbirl_messages == 0) && log.handle(0) >= 0) {
  }
  log.unsubscribe(all);
  if (!key) {
    if (signed_messages + old_format > 0) {
      throw InputError("--key", "the messages in '" + log_path +
                                    "' are signed with a run key: give it (launch.sh wrote OUT/run.key)");
    }
    return;
  }
  if (signed_messages == 0) {
    throw InputError(
        "--key",
        old_format > 0
            ? "'" + log_path + "' was signed in the format before run identities (hbk1): this hbirl cannot check it"
            : "the messages in '" + log_path + "' are not signed: read it without --key");
  }
  if (with_key == 0) {
    throw InputError("--key", "none of the " + std::to_string(signed_messages) + " signed messages in '" + log_path +
                                  "' is signed with the key in '" + key_file +
                                  "': the wrong key (a run's key is OUT/run.key, beside its recording)");
  }
  if (!found) {
    throw InputError("--key", "'" + key_file + "' is the key file of run " + run_id_text(*key->run()) + ", and '" +
                                  log_path + "' holds run " + run_id_text(recorded_run) +
                                  ": give that run's key file (OUT/run.key beside its recording)");
  }
}

std::unique_ptr<Bus> with_key(std::unique_ptr<Bus> bus, const std::string& key_file, Counters& counters, KeyUse use) {
  if (key_file.empty()) {
    counters.authenticated = false;
    if (use != KeyUse::kReader)
      counters.note(
          "the bus is unauthenticated (no --key): any process on the multicast group can publish to this run "
          "(docs/RELIABILITY.md)");
    return bus;
  }
  const RunKey key = RunKey::read(key_file);
  if (!key.run() && use == KeyUse::kService) {
    throw InputError("--key", "'" + key_file +
                                  "' names no run (a key for many runs): services/launch.sh writes each run its own "
                                  "OUT/run.key; hbirl keygen --run-of '" +
                                  key_file + "' FILE makes one by hand");
  }
  return std::make_unique<KeyedBus>(std::move(bus), key, counters, use);
}

}  // namespace hbirl::services
