#pragma once
// Knowing when it has seen enough, measured (`hbirl experiment stopping`,
// docs/results/stopping): tasks (random, or a figure's runs: judged_tasks.hpp) learned while their demonstrations
// arrive (app::learn_anytime, with the posterior's confidence after each), then the stop rule (app::StopRule: k
// estimates in a row with confidence >= p) applied to the sequence -- after how many demonstrations it stops, and
// whether the policy it stops with is right (within 5% of the optimal value), against the policy learned from every
// demonstration.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "app/learn.hpp"
#include "learner/reward_posterior.hpp"

namespace hbirl {

struct StoppingOptions {
  int tasks = 60;
  std::uint64_t first_seed = 8001;     // not a seed anything was tuned on
  std::string tasks_from = "random";   // random, gridworld or onion (judged_tasks.hpp)
  int samples = kLiveConfidenceDraws;  // posterior draws per estimate, as the live optimiser's
  std::vector<double> levels = {0.9, 0.95};
  int stop_after = app::StopRule::kDefaultAfter;
  int threads = 0;
  std::function<void(int done, int total)> progress;  // called from worker threads
};

// One task's sequence of estimates, from its observations.
struct StoppingRun {
  std::uint64_t seed = 0;
  int draw = 0;
  std::vector<double> confidence;    // after 1, 2, ... demonstrations
  std::vector<double> ile_relative;  // of each estimate's policy
  double seconds = 0.0;
  std::string error;
};

std::vector<StoppingRun> run_stopping(const StoppingOptions& options);

// One row per estimate: seed, draw, demonstrations, confidence, ile_relative, right.
std::string stopping_runs_csv(const std::vector<StoppingRun>& runs);
// The runs back from that CSV; InputError naming the line for anything else.
std::vector<StoppingRun> stopping_runs_from_csv(const std::string& csv);

// The summary page (markdown): per level p, how many tasks the rule stopped, after how many
// demonstrations (median and quartiles, and the share of the task's demonstrations), how
// often the policy it stopped with is right, and how often the policy from every
// demonstration is right.
std::string stopping_summary(const std::vector<StoppingRun>& runs, const StoppingOptions& options,
                             const std::string& footer);

// Figure: share right against demonstrations seen (all tasks), and where the rule stopped.
std::string draw_stopping_figure(const std::vector<StoppingRun>& runs, const StoppingOptions& options,
                                 const std::string& path_stem);

}  // namespace hbirl
