#pragma once
// Is hbirl's confidence a promise? (`hbirl experiment calibration`, docs/results/calibration.)
// Random tasks (sim_driver/file/random_task.hpp) or a figure's runs (judged_tasks.hpp), each data set learned as `hbirl
// learn` learns it (app::learn, from the observations and from the true trajectories) with
// --posterior-samples; the confidence -- the posterior probability that the learned policy
// is within 5% of the optimal value -- against whether it is (relative ILE <= 0.05 under
// the true reward). Scored by the expected calibration error (ECE, 10 equal-width bins),
// the Brier score, the AUROC of the confidence for right against wrong, and of the runs
// with confidence >= 0.9 the share right; drawn as a reliability diagram.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "learner/reward_posterior.hpp"

namespace hbirl {

struct CalibrationOptions {
  int tasks = 200;
  // Not the seeds the posterior's defaults were looked at on (1001-1060, docs/MODEL.md).
  std::uint64_t first_seed = 5001;
  int draws = 3;                                              // data sets per task
  int samples = kConfidenceDraws;                             // posterior draws per run
  double prior_scale = RewardPosteriorOptions{}.prior_scale;  // hbirl learn's default; 0: chosen by the evidence
  std::vector<std::string> data = {"observations", "truth"};
  // Learn from the first n demonstrations of each data set, for each n here (a run each);
  // empty: from every demonstration (a run's `demonstrations` is then 0).
  std::vector<int> demonstrations;
  // Where the tasks come from: random, gridworld or onion (judged_tasks.hpp; a figure's run
  // is one data set, with the seed `first_seed`).
  std::string tasks_from = "random";
  int threads = 0;
  std::function<void(int done, int total)> progress;  // called from worker threads
};

struct CalibrationRun {
  std::uint64_t seed = 0;
  int draw = 0;
  int demonstrations = 0;  // learned from the first this many (0: every one)
  std::string data;        // "observations" or "truth"
  double confidence = 0.0;
  double probability_optimal = 0.0;
  double expected_ile_relative = 0.0;
  double ile_relative = 0.0;
  bool right = false;  // ile_relative <= 0.05
  double prior_scale = 0.0;
  double effective_samples = 0.0;
  double seconds = 0.0;
  std::string error;
};

std::vector<CalibrationRun> run_calibration(const CalibrationOptions& options);

std::string calibration_runs_csv(const std::vector<CalibrationRun>& runs);
// The runs back from that CSV; InputError naming the line for anything else.
std::vector<CalibrationRun> calibration_runs_from_csv(const std::string& csv);

// How well probabilities p_i predict outcomes y_i.
struct ReliabilityBin {
  double lo = 0.0, hi = 0.0;  // [lo, hi), the last closed
  int runs = 0;
  int right = 0;
  double mean_confidence = 0.0;
};
struct CalibrationScore {
  int runs = 0;
  int right = 0;
  double mean_confidence = 0.0;
  double ece = 0.0;    // sum over bins of (runs / N) |mean confidence - share right|
  double brier = 0.0;  // mean (p - y)^2
  double auroc = 0.5;  // P(p of a right run > p of a wrong one), ties half
  int confident = 0;   // runs with p >= 0.9
  int confident_right = 0;
  std::vector<ReliabilityBin> bins;  // 10 equal-width
};
CalibrationScore calibration_score(const std::vector<double>& confidence, const std::vector<bool>& right);

// The summary page (markdown): per data the score, its reliability table, and the runs
// that were confident and wrong. `footer` goes at the end.
std::string calibration_summary(const std::vector<CalibrationRun>& runs, const std::string& footer);

// Figure: the reliability diagram (share right against confidence, per data, with 95%
// Wilson intervals, and the diagonal) over the histogram of confidences (gnuplot).
// Returns "" on success, else why no figure was drawn.
std::string draw_calibration_figure(const std::vector<CalibrationRun>& runs, const std::string& path_stem);

}  // namespace hbirl
