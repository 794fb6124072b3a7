// libFuzzer target: a recording (an lcm-logger file) as the readers of a run read it --
// the key check, the data set collected to its end (hbirl learn / export --log, with
// --allow-incomplete so that a run cut short is still read) and the dashboard's following
// reader (services/log_bus.hpp). Every header must be checked before anything is allocated
// for it; what cannot be used is one InputError. The input is the file (an anonymous
// in-memory one: memfd).
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "learner/input_error.hpp"
#include "services/keyed_bus.hpp"
#include "services/log_bus.hpp"
#include "services/optimiser.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hbirl::services;
  if (size > (1u << 22)) return 0;
  const int fd = ::memfd_create("recording", MFD_CLOEXEC);
  if (fd < 0) return 0;
  if (size > 0 && ::write(fd, data, size) != static_cast<ssize_t>(size)) {
    ::close(fd);
    return 0;
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  Counters counters;
  counters.service = "fuzz";
  counters.quiet = true;
  try {
    check_recording_key(path, "");
    collect_from_log(RecordedRun{path, "", true}, counters);
  } catch (const hbirl::InputError&) {
  }
  try {
    LogBus following(path);
    following.follow(true);
    int events = 0;
    following.subscribe(".*", [&events](const Message&) { ++events; });
    for (int k = 0; k < 64; ++k) following.handle(0);
  } catch (const hbirl::InputError&) {
  }
  ::close(fd);
  return 0;
}
