// hbirl's heap on transparent huge pages (docs/BENCHMARKS.md, "Huge pages"). glibc (2.35
// on) puts the heap on them when the tunable glibc.malloc.hugetlb=1 is set, and reads
// tunables only when a process starts; so hbirl runs itself again with it set, once,
// before anything else. Where page faults are dear -- on this machine's virtual CPU they
// were ~40% of reading a 200x200 problem file -- one fault then maps 2 MB instead of 4 kB.
// The results are the same bits: only where memory comes from changes.
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "commands.hpp"

namespace hbirl::cli {

void use_huge_pages(char** argv) {
  const char* setting = std::getenv("HBIRL_HUGE_PAGES");
  if (setting != nullptr && std::strcmp(setting, "0") == 0) return;  // off (to measure it)
  const char* given = std::getenv("GLIBC_TUNABLES");
  std::string tunables = given != nullptr ? given : "";
  if (tunables.find("glibc.malloc.hugetlb=") != std::string::npos) return;  // set: by us, or as the user wants
  tunables += (tunables.empty() ? "" : ":") + std::string("glibc.malloc.hugetlb=1");
  if (setenv("GLIBC_TUNABLES", tunables.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  unsetenv("GLIBC_TUNABLES");  // could not run again: carry on as started
  if (given != nullptr) setenv("GLIBC_TUNABLES", given, 1);
}

}  // namespace hbirl::cli
