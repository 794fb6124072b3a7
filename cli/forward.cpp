// The commands of `hbirl` that run in `hbirl-full` (full_commands.hpp): hbirl replaces
// itself with hbirl-full, found next to it, given the same arguments; so `hbirl learn`
// loads no OpenCV, LCM or libsodium, and `hbirl render ...` works as ever.
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.hpp"
#include "full_commands.hpp"
#include "generate_args.hpp"
#include "learn_args.hpp"

namespace hbirl::cli {

namespace {
std::vector<char*> arguments;  // main's argv, as given
}  // namespace

void remember_arguments(int argc, char** argv) {
  arguments.assign(argv, argv + argc);
  arguments.push_back(nullptr);
}

int run_in_full() {
  char self[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) throw std::runtime_error(std::string("cannot find where hbirl is: ") + std::strerror(errno));
  std::string path(self, static_cast<size_t>(n));
  path = path.substr(0, path.rfind('/') + 1) + "hbirl-full";
  std::vector<char*> args = arguments;
  args[0] = path.data();
  std::cout.flush();
  execv(path.c_str(), args.data());
  throw std::runtime_error("cannot run " + path + " (" + std::strerror(errno) +
                           "): it is built with hbirl (cmake --build build --target hbirl)");
}

Command add_forwarded(CLI::App& app, const FullCommand& command) {
  CLI::App* cmd = app.add_subcommand(command.name, command.description);
  cmd->set_help_flag();   // --help too goes to hbirl-full, which has the command's options
  cmd->prefix_command();  // every argument after the command, as given
  return [] { return run_in_full(); };
}

int run_learn_from_log(const LearnArgs&) { return run_in_full(); }

int run_generate_from_domain(const GenerateDomainArgs&) { return run_in_full(); }

}  // namespace hbirl::cli
