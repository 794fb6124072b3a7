// Test helper: publishes junk on LCM channels -- random bytes, and a valid message of the
// wrong type -- to check that services count bad input and keep running.
//   lcm_inject URL CHANNEL [CHANNEL...]
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "hbirl/service_status_t.hpp"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: lcm_inject URL CHANNEL...\n");
    return 2;
  }
  lcm::LCM lcm(argv[1]);
  if (!lcm.good()) return 1;
  hbirl::service_status_t wrong{};
  wrong.service = "not-what-you-expect";
  std::vector<unsigned char> junk(300);
  for (size_t i = 0; i < junk.size(); ++i) junk[i] = static_cast<unsigned char>(i * 131 + 7);
  int sent = 0;
  for (int c = 2; c < argc; ++c) {
    for (int k = 0; k < 3; ++k) {
      sent += lcm.publish(argv[c], junk.data(), static_cast<unsigned>(junk.size() - static_cast<size_t>(k * 50))) == 0;
      sent += lcm.publish(argv[c], &wrong) == 0;
    }
  }
  std::printf("%d\n", sent);
  return 0;
}
