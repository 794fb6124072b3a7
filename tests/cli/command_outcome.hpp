#pragma once
// A command as a user meets it: its exit status and what it wrote to stdout and stderr
// (tests of the hbirl commands, tests/cli/).
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace hbirl::testing {

struct Outcome {
  int status = -1;  // the exit status (-1: ended by a signal)
  std::string out, err;
  int err_lines() const { return static_cast<int>(std::count(err.begin(), err.end(), '\n')); }
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs the shell command `command` with stdout and stderr sent to files in `dir`.
inline Outcome run_command(const std::string& command, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "stdout", err = dir / "stderr";
  const int raw = std::system((command + " >'" + out.string() + "' 2>'" + err.string() + "'").c_str());
  Outcome r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

}  // namespace hbirl::testing
