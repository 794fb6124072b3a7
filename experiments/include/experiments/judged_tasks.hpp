#pragma once
// The tasks hbirl's confidence is judged on (`hbirl experiment calibration` and `stopping`,
// --tasks-from): what the learner is given and the truth its answer is judged by, from
//   random     random tasks (sim_driver/file/random_task.hpp): task seeds first_seed + t,
//              data sets (draws) 0 .. draws - 1 of each
//   gridworld  the Gridworld figure's run t of the seed first_seed (paper §Experiments A,
//              gridworld_scenario.hpp): 5x5, 20 demonstrations of 10 steps, 40 observations
//              a step, plausible eta, the controlled run's subject prior, |E| = 0, 1, 3, ...,
//              15 in turn (the draw is |E|)
//   onion      the onion figure's run t of the seed first_seed (paper §Experiments B,
//              onion_experiment.hpp): 10 sorts rendered, perceived and labelled in the scene
//              with all three elements and the mirror, the labeller's eta, the subject prior
//              of a controlled run of 20 sorts (draw 0)
// A figure's run is one data set: `draws` is for random tasks only. Task t's data set has
// the seed first_seed + t whatever the source, and the learner's seed comes from (seed, draw).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "experiments/data_sets.hpp"
#include "learner/mdp.hpp"
#include "learner/observations.hpp"
#include "learner/trajectory.hpp"

namespace hbirl {

struct JudgedTask {
  Mdp mdp;
  std::vector<ObservedTrajectory> observed;  // one per demonstration, in order
  ObservationPrior prior;
  std::vector<Trajectory> truth;  // the demonstrations' true steps, in the same order
  Eigen::VectorXd true_weights;
};

struct JudgedTaskOptions {
  std::string source = "random";  // random, gridworld or onion
  int tasks = 200;
  std::uint64_t first_seed = 5001;
  int draws = 3;  // data sets per random task
};

const std::vector<std::string>& judged_task_sources();
// What a summary calls a source's tasks ("Random tasks", "The Gridworld figure's runs ...").
std::string judged_task_label(const std::string& source);
// The figure's own seed for a figure's runs (its runs are those of that seed); none for random tasks.
std::optional<std::uint64_t> figure_seed(const std::string& source);
// Which tasks `options` names, for a footer: "seeds 5001-5200 x 3 data sets each", or for a
// figure "runs 0-89 of the seed 1 (task t is run t; the figure has 65)".
std::string judged_task_span(const JudgedTaskOptions& options);
// The command that writes a data set (seed S, draw D) as a problem file, for a footer's
// "reproduce one"; none where there is no such command (a figure's runs).
std::optional<std::string> judged_task_problem_command(const std::string& source);

// The data sets of `options`, in order; InputError naming "tasks_from" for an unknown source.
std::vector<DataSetId> judged_data_sets(const JudgedTaskOptions& options);

// Makes a data set's task (what every data set of a source shares, as the onion's controlled
// run, is made once). Safe to call from several threads at once.
class JudgedTaskMaker {
 public:
  explicit JudgedTaskMaker(const JudgedTaskOptions& options);
  ~JudgedTaskMaker();
  JudgedTask operator()(const DataSetId& id) const;

  struct Shared;  // what a source's data sets share (judged_tasks.cpp)

 private:
  JudgedTaskOptions options_;
  std::unique_ptr<const Shared> shared_;
};

// `variants` runs on each data set of `options` (on_data_sets).
template <class Run, class Learn>
std::vector<Run> on_judged_tasks(const JudgedTaskOptions& options, size_t variants, int threads,
                                 const std::function<void(int, int)>& progress, const Learn& learn) {
  const std::vector<DataSetId> ids = judged_data_sets(options);
  const JudgedTaskMaker make(options);
  return on_data_sets<Run>(ids, variants, threads, progress, make, learn);
}

}  // namespace hbirl
