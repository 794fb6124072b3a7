#include "services/process.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

namespace hbirl::services {
namespace {

double modified(const std::filesystem::path& p) {
  struct stat st {};
  if (::stat(p.c_str(), &st) != 0) return -1.0;
  return static_cast<double>(st.st_mtim.tv_sec) + 1e-9 * static_cast<double>(st.st_mtim.tv_nsec);
}

// The alive file a supervisor watches (services/launch.sh --stall-timeout): touched while
// the process beats its heartbeat or computes -- an M-step on a big task sends no
// heartbeat for seconds, and was killed as "silent" when only heartbeats counted -- and
// left alone while it does neither (stopped, or blocked for good).
TEST(Process, TheAliveFileFollowsHeartbeatsAndWorkNotSilence) {
  const auto path = std::filesystem::temp_directory_path() / ("hbirl-alive-" + std::to_string(::getpid()));
  std::filesystem::remove(path);
  set_alive_file(path.string());
  ASSERT_GT(modified(path), 0.0);
  // Computing, no heartbeat: touched.
  const double computing_from = modified(path);
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(2500);
  volatile double sink = 0.0;
  while (std::chrono::steady_clock::now() < until) sink = sink + 1.0;
  EXPECT_GT(modified(path), computing_from + 0.5) << "a process computing was not seen as alive";
  // Heartbeats while idle: touched.
  const double beating_from = modified(path);
  for (int k = 0; k < 5; ++k) {
    touch_alive_file();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  EXPECT_GT(modified(path), beating_from + 0.5) << "heartbeats did not touch the file";
  // Neither (as a stopped or blocked process): not touched.
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));  // the watchdog's last look at the beats above
  const double silent_from = modified(path);
  std::this_thread::sleep_for(std::chrono::milliseconds(3000));
  EXPECT_EQ(modified(path), silent_from) << "a silent process was seen as alive";
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace hbirl::services
