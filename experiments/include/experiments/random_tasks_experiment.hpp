#pragma once
// hbirl on tasks nobody tuned it for (`hbirl experiment random-tasks`,
// docs/results/random_tasks): random MDPs, rewards and sensors (sim_driver/file/random_task.hpp),
// each learned by
//   true_trajectories  MaxCausalEnt on the true (s, a): what the data could give at best
//   fixed_prior        O fixed at the prior's mean (the controlled run; observation_model.learn false)
//   paper_c0.5, paper_c0.1   the paper's update alpha = c alpha_dot + (1 - c) alpha
//   posterior          the default: the Dirichlet posterior (prior kept), the subject prior's
//                      strength chosen by held-out likelihood, eta learned; c = 0.1
//   posterior_c0.5, posterior_c0.02  the same with c = 0.5, 0.02 (the paper's step size,
//                      which the posterior update does not use: the answer must not change)
//   posterior_r4       the default with 4 restarts instead of 1 (do restarts change the answer?)
//   oracle_sensor      what the simulator used, nothing learned: the true subject O and element
//                      O's, every observation's eta what its stated eta says of the true
//                      source under the simulator's rules (calibrated_eta) -- the best
//                      learning from observations could reach with this model
//   oracle_sensor_end  the same, also told which terminal state each trajectory entered when
//                      it entered one (a goal or a trap): the part of the gap to
//                      true_trajectories that a sensor seeing which would close
//   posterior_end      the default, with a sensor that sees which terminal state each
//                      trajectory entered (ObservedTrajectory::end_state): what such a
//                      sensor buys the learner as it is
//   posterior_end_sensor  the default with the task's noisy end sensor (random_task.hpp
//                      "end"): 1-3 reports per ending, O_end learned from the controlled
//                      run's prior (docs/MODEL.md "Sensors that see the end")
//   oracle_end_sensor  oracle_sensor with the same reports and the true O_end
//   oracle_o           the true subject O and element O's held fixed, eta learned as the
//                      default learns it: the default's gap to oracle_sensor split into
//                      what O's estimate costs and what eta's does
//   oracle_subject_o   the true subject O held, the elements' O's and eta learned as the
//                      default learns them; oracle_elements_o: the true element O's held,
//                      the subject's O and eta learned: O's part split between the two
//   oracle_seen_subject_o  the true subject O held on the pairs the controlled run saw
//                      only (the others kept at the prior's mean, as the default keeps them),
//                      the strength fixed at 1: compare with posterior_s1
//   oracle_unseen_subject_o  its complement: the true subject O held on the pairs the
//                      controlled run never saw, the others its counts at strength 1
//   posterior_unheld   the default with the pairs the controlled run never saw learned
//                      from the demonstrations instead of held at the prior's mean
//   posterior_base0.1, posterior_base0.3  the default with a base pseudo-count of 0.1 or
//                      0.3 per symbol instead of the stated 1: less pull towards uniform on
//                      the seen pairs, and the unseen ones held at 1000 b instead of 1000
//   posterior_s1, posterior_s1000  the default with the subject prior's strength fixed
//                      at 1 (the counts at face value) or 1000 (the controlled run's O
//                      held) instead of chosen by held-out likelihood
//   posterior_from_truth  the default, its first E-step at oracle_sensor's O's and eta
//                      instead of the prior's mean and the stated eta: does the data's
//                      likelihood keep EM at the truth, and does the learner's criterion
//                      prefer it to the default's answer?
//   posterior_cross_fit  the default with cross-fitted E-step passes (each trajectory's
//                      posterior under the O of the others' expected counts)
//   posterior_elements0.1 .. posterior_elements1000  the default with the elements' flat
//                      prior weighed 0.1-1000 times
//   oracle_labelled_o, oracle_sensor_labelled_o  O at what the data set says of it with
//                      every label revealed (the controlled run's counts and each
//                      observation at its true (s, a) or element, labelled_counts), held while eta is
//                      learned / with oracle_sensor's eta. Each trajectory's own symbols
//                      then point its posterior at its true path: not a limit, a leak
//   oracle_sensor_labelled_o_cf  each trajectory's posterior under the labelled O of the
//                      controlled run and the other demonstrations only (oracle_sensor's eta)
//   oracle_sensor_labelled_others  that O as the prior of each trajectory's own O, learned
//                      from its own observations by the posterior update (strength 1,
//                      oracle_sensor's eta; the pairs the controlled run never saw held)
//   oracle_sensor_own_o  the same on the controlled run's prior alone: what the other
//                      trajectories' labels add to it, all else equal
// with one observation-model refinement per E-step (the paper experiments' schedule) and
// hbirl learn's tolerances (1e-4 on theta and O, 1e-7 on the objective; up to 3000 EM
// iterations). A run is "optimal" when the learned reward's optimal
// policy is optimal under the true reward (ILE 0 to 1e-8 of the value scale).
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "experiments/data_sets.hpp"
#include "learner/observation_model.hpp"
#include "sim_driver/file/random_task.hpp"

namespace hbirl {

struct RandomTaskMethod {
  std::string key;   // as above
  std::string kind;  // "truth", "fixed", "paper", "posterior", "oracle", "oracle_o",
                     // "oracle_subject_o", "oracle_elements_o", "oracle_seen_subject_o",
                     // "oracle_unseen_subject_o", "unheld", "from_truth", "labelled_o",
                     // "oracle_labelled", "oracle_labelled_cf", "oracle_labelled_others",
                     // "oracle_own_o"
  double c = 0.1;
  int restarts = 1;
  // What was seen of how each trajectory ended, besides that it did: nothing, the terminal
  // state entered (ObservedTrajectory::end_state), or the task's end sensor's reports.
  enum class End { kUnseen, kState, kSensor };
  End end = End::kUnseen;
  double strength = 0.0;   // the subject prior's strength; 0: chosen from the data (the default)
  double base = -1.0;      // the subject prior's base pseudo-count instead of the stated one (-1: as stated)
  bool cross_fit = false;  // cross-fitted E-step passes (ObservationEStepOptions::cross_fit)
  double elements = 1.0;   // the elements' prior (confounder_alpha) times this; the task's is 1 per symbol
  bool tie = false;        // the subject prior tied across a state's actions (ObservationPrior::tie_actions)
};

const std::vector<RandomTaskMethod>& all_random_task_methods();

// Demonstration i's labelled counts: each of its observations' symbol counted at its true
// (s, a) (subject) or its true element (confounders), with its weight; no end counts.
// What a labeller that knew every source and every step would add to O's Dirichlet prior
// (the labelled oracles above).
AlphaCounts labelled_counts(const RandomTask& task, size_t i);
// The prior of demonstration i's O in the labelled oracles that leave it out: the
// controlled run's (task.prior's subject and element parameters) plus every other
// demonstration's labelled_counts.
AlphaCounts others_labelled_prior(const RandomTask& task, size_t i);
// The listed keys (comma-separated) or "all"; throws InputError naming an unknown key.
std::vector<RandomTaskMethod> parse_random_task_methods(const std::string& keys);

struct RandomTasksOptions {
  int tasks = 200;  // task seeds first_seed .. first_seed + tasks - 1
  std::uint64_t first_seed = 1;
  std::vector<std::uint64_t> seeds;  // these task seeds instead, when not empty
  int draws = 3;                     // data sets per task
  int controlled = -1;               // trajectories of every task's controlled run (-1: as drawn, 5-30)
  int demonstrations = -1;           // demonstrations of every data set (-1: as drawn, 5-40)
  std::vector<RandomTaskMethod> methods = all_random_task_methods();
  int threads = 0;
  std::function<void(int done, int total)> progress;  // called from worker threads
};

struct RandomTaskRun {
  std::uint64_t seed = 0;
  int draw = 0;
  std::string method;
  // The task.
  std::string layout;
  int states = 0, actions = 0, features = 0, goals = 0, traps = 0;
  int symbols = 0, confounders = 0, per_step = 0, demonstrations = 0, controlled = 0;
  double decisiveness = 0.0, informativeness = 0.0, subject_share = 0.0, occlusion = 0.0, discount = 0.0;
  std::string eta;
  // The result.
  double ile = 0.0;
  double ile_relative = 0.0;
  bool optimal = false;
  double policy_agreement = 0.0;
  int em_evaluations = 0;
  bool converged = false;
  double log_likelihood = 0.0;
  double strength = -1.0;  // the posterior update's chosen prior strength; -1 if n/a
  // The learner's own criterion for the returned point (RestartResult::score: the held-out
  // log-likelihood that chose the strength, else EM's objective); NaN in runs from before
  // it was recorded.
  double score = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> theta;
  double seconds = 0.0;
  std::string error;
};

// `variants` runs on each data set (task seed, draw) of random tasks (on_data_sets).
template <class Run, class Learn>
std::vector<Run> on_random_data_sets(const std::vector<std::uint64_t>& seeds, int draws, size_t variants, int threads,
                                     const std::function<void(int, int)>& progress, const Learn& learn,
                                     const RandomTaskOverrides& overrides = {}) {
  std::vector<DataSetId> ids;
  for (std::uint64_t seed : seeds) {
    for (int d = 0; d < draws; ++d) ids.push_back({seed, d});
  }
  return on_data_sets<Run>(
      ids, variants, threads, progress,
      [&overrides](const DataSetId& id) { return make_random_task(id.seed, id.draw, overrides); }, learn);
}

std::vector<RandomTaskRun> run_random_tasks(const RandomTasksOptions& options);

std::string random_task_runs_csv(const std::vector<RandomTaskRun>& runs);
// The runs back from that CSV (to summarise and draw a committed run again); InputError
// naming the line for anything else.
std::vector<RandomTaskRun> random_task_runs_from_csv(const std::string& csv);

// The summary page (markdown): per method the share of optimal runs (95% Wilson
// interval) and the relative ILE, broken down by confounders, occlusion, sensor
// informativeness and eta; paired comparisons; whether the default depends on c; what
// restarts change. `footer` goes at the end.
std::string random_tasks_summary(const std::vector<RandomTaskRun>& runs, const std::string& footer);

// Figure: share of optimal runs per method, overall and by each breakdown (gnuplot).
// Returns "" on success, else why no figure was drawn.
std::string draw_random_tasks_figure(const std::vector<RandomTaskRun>& runs, const std::string& path_stem);

}  // namespace hbirl
