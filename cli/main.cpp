// hbirl: learn an expert's reward from noisy, confounded observations.
// Exit status: 0 success, 2 bad input or usage (one line on stderr, nothing on stdout),
// 1 internal error.
#include <cerrno>
#include <cstring>
#include <iostream>

#include "commands.hpp"
#include "full_commands.hpp"
#include "learner/input_error.hpp"

namespace {
constexpr const char* kDescription =
    "hbirl: hierarchical Bayesian inverse reinforcement learning in partially-controlled\n"
    "environments (Bogert & Doshi, IROS 2021). It learns the reward weights of an expert\n"
    "from a problem file: an MDP, a demonstration (observations with source distributions\n"
    "eta, and/or the true state-action trajectories) and optional true weights for metrics.\n"
    "The problem-file format is documented in docs/files.md (\"Problem files\").\n";
}

int main(int argc, char** argv) {
  CLI::App app{kDescription, "hbirl"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("hbirl ") + HBIRL_VERSION);
  app.footer(
      "Run 'hbirl SUBCOMMAND --help' for a subcommand's options.\n"
      "Exit status: 0 success, 2 bad input or usage, 1 internal error.");
  std::vector<std::pair<CLI::App*, hbirl::cli::Command>> commands;
  auto remember = [&](hbirl::cli::Command command) {
    commands.emplace_back(app.get_subcommands({}).back(), std::move(command));
  };
  remember(hbirl::cli::add_learn(app));
  remember(hbirl::cli::add_posterior(app));
  remember(hbirl::cli::add_generate(app));
  remember(hbirl::cli::add_summary(app));
#ifdef HBIRL_FULL
  remember(hbirl::cli::add_validate(app));
  remember(hbirl::cli::add_experiment(app));
  remember(hbirl::cli::add_render(app));
  remember(hbirl::cli::add_report(app));
  remember(hbirl::cli::add_publish(app));
  remember(hbirl::cli::add_export(app));
  remember(hbirl::cli::add_keygen(app));
#else
  // These run in hbirl-full: the learning commands need none of what it loads.
  hbirl::cli::remember_arguments(argc, argv);
  for (const hbirl::cli::FullCommand& command : hbirl::cli::kFullCommands)
    remember(hbirl::cli::add_forwarded(app, command));
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version: stdout, status 0
    std::cerr << "hbirl: error: " << e.what() << " (run 'hbirl --help')\n";
    return 2;
  }
  int status = 2;
  try {
    for (auto& [sub, command] : commands) {
      if (sub->parsed()) status = command();
    }
  } catch (const hbirl::InputError& e) {
    std::cerr << "hbirl: error: " << hbirl::printable(e.what()) << "\n";
    return 2;
  } catch (const hbirl::cli::OutputError& e) {
    std::cerr << "hbirl: error: could not write the output: " << hbirl::printable(e.what()) << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "hbirl: internal error: " << hbirl::printable(e.what()) << "\n";
    return 1;
  }
  // Output that did not get out (a full disk, a closed pipe) is a failure, not a result.
  errno = 0;
  std::cout.flush();
  if (!std::cout) {
    std::cerr << "hbirl: error: could not write the output: " << std::strerror(errno ? errno : EIO) << "\n";
    return 1;
  }
  return status;
}
