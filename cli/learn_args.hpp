#pragma once
// hbirl learn's options, shared by the command (learn_command.cpp) and its part that reads
// a recorded run (learn_log.cpp: it links the service set, so it runs in hbirl-full).
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "learner/observations.hpp"

namespace hbirl::cli {

struct LearnArgs {
  std::string problem;
  std::string log;
  std::string key_file;       // --log: the run's key
  bool allow_incomplete = false;
  DomainArgs domain;  // --log: the domain file of a run on one (built-in domains come from the log)
  std::string from = "observations";
  std::string optimizer = "lbfgs";
  double l2 = 0.0;
  int restarts = 1;  // more changed nothing on average on the random tasks (docs/results/random_tasks)
  std::uint64_t seed = 1;
  int threads = 0;
  int max_iterations = 1000;
  double tolerance = 1e-9;
  double eg_radius = 50.0;
  double eg_rate = 0.25;
  EngineArgs engine;
  int max_em_iterations = 300;
  double alpha_tolerance = 1e-4;
  int max_alpha_iterations = 10;
  AlphaUpdate update = AlphaUpdate::kPosterior;
  bool update_given = false;  // --alpha-update overrides the file's observation_model.update
  bool verbose = false;
  std::string eta = "file";  // "stated", "learned", or as the file's observation_model.learn_eta says
  std::string out;
};

// hbirl learn --log: learns from a recorded run as hbirl-optimiser does. In `hbirl` it runs
// hbirl-full with the same arguments (forward.cpp).
int run_learn_from_log(const LearnArgs& args);

}  // namespace hbirl::cli
