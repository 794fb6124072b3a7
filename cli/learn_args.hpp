#pragma once
// hbirl learn's options, shared by the command (learn_command.cpp) and its part that reads
// a recorded run (learn_log.cpp: it links the service set, so it runs in hbirl-full).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/command_line.hpp"
#include "commands.hpp"

namespace hbirl::cli {

struct LearnArgs {
  std::string problem;
  std::string log;
  std::string key_file;  // --log: the run's key
  bool allow_incomplete = false;
  app::DomainArgs domain;  // --log: the domain file of a run on one (built-in domains come from the log)
  std::string from = "observations";
  app::LearnSettings settings;     // every learning setting (app/learn_settings.hpp)
  int demonstrations = 0;          // learn from the first this many (0: all)
  std::vector<double> warm_start;  // EM also starts from these weights
  bool anytime = false;            // an estimate after each demonstration
  bool verbose = false;
  std::string out;
};

// hbirl learn --log: learns from a recorded run as hbirl-optimiser does. In `hbirl` it runs
// hbirl-full with the same arguments (forward.cpp).
int run_learn_from_log(const LearnArgs& args);

}  // namespace hbirl::cli
