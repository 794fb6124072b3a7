// Test helper: hostile messages on LCM channels, to check that services count bad input
// and keep running (tests/services/netns_test.sh, case bad_input; docs/RELIABILITY.md).
//   lcm_inject URL CHANNEL [CHANNEL...]   random bytes and a valid message of the wrong
//                                         type on each channel, then the channel's own type
//                                         with every 4 bytes in turn replaced by INT_MIN (a
//                                         hostile string or array length)
//   lcm_inject --log FILE                 the same hostile messages, every channel, written
//                                         into an lcm-logger file (a poisoned recording)
#include <chrono>
#include <climits>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "hbirl/service_status_t.hpp"
#include "sample_messages.hpp"
#include "services/channels.hpp"

namespace {

// Every channel's own message type, each 4 bytes after the fingerprint set to INT_MIN in turn.
std::vector<std::vector<std::uint8_t>> hostile_variants(const hbirl::test::SampleMessage& sample) {
  std::vector<std::vector<std::uint8_t>> out;
  for (size_t at = 8; at + 4 <= sample.bytes.size(); ++at)
    out.push_back(hbirl::test::with_int32_at(sample.bytes, at, INT_MIN));
  return out;
}

int write_log(const std::string& path) {
  lcm::LogFile log(path, "w");
  if (!log.good()) return 1;
  int written = 0;
  std::int64_t utime = 1;
  for (const auto& sample : hbirl::test::sample_messages()) {
    for (auto& bytes : hostile_variants(sample)) {
      lcm::LogEvent event{};
      event.eventnum = written;
      event.timestamp = utime++;
      event.channel = sample.channel;
      event.datalen = static_cast<std::int32_t>(bytes.size());
      event.data = bytes.data();
      written += log.writeEvent(&event) == 0;
    }
  }
  std::printf("%d\n", written);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--log") return write_log(argv[2]);
  if (argc < 3) {
    std::fprintf(stderr, "usage: lcm_inject URL CHANNEL...  |  lcm_inject --log FILE\n");
    return 2;
  }
  lcm::LCM lcm(argv[1]);
  if (!lcm.good()) return 1;
  hbirl::service_status_t wrong{};
  wrong.service = "not-what-you-expect";
  std::vector<unsigned char> junk(300);
  for (size_t i = 0; i < junk.size(); ++i) junk[i] = static_cast<unsigned char>(i * 131 + 7);
  const auto samples = hbirl::test::sample_messages();
  int sent = 0;
  for (int c = 2; c < argc; ++c) {
    // TRAJECTORY:ID: the trajectory samples on the channel of the sampler worker ID.
    const std::string arg = argv[c];
    const bool trajectories = arg.rfind("TRAJECTORY:", 0) == 0;
    const std::string channel = trajectories ? hbirl::services::channels::trajectory_channel(arg.substr(11)).name : arg;
    const std::string samples_of = trajectories ? "TRAJECTORY" : arg;
    for (int k = 0; k < 3; ++k) {
      sent += lcm.publish(channel, junk.data(), static_cast<unsigned>(junk.size() - static_cast<size_t>(k * 50))) == 0;
      sent += lcm.publish(channel, &wrong) == 0;
    }
    for (const auto& sample : samples) {
      if (sample.channel != samples_of) continue;
      int n = 0;
      for (const auto& bytes : hostile_variants(sample)) {
        sent += lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())) == 0;
        // Paced: a receiver's queue (30 messages by default in LCM) drops the rest of a burst.
        if (++n % 20 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    }
  }
  std::printf("%d\n", sent);
  return 0;
}
