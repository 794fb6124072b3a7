// The Gridworld as a problem file (problem_file.hpp).
#include "sim_driver/gridworld/problem_file.hpp"

#include <string>

#include "learner/input_error.hpp"
#include "sim_driver/gridworld/gridworld.hpp"

namespace hbirl {

namespace {

void check_range(const char* name, double value, double low, double high) {
  if (!(value >= low && value <= high)) {
    throw InputError(name,
                     std::to_string(value) + " is not in [" + std::to_string(low) + ", " + std::to_string(high) + "]");
  }
}

void check(const GridworldProblemOptions& o) {
  check_range("size", o.size, 2, 1000);
  check_range("trajectories", o.trajectories, 1, 10000000);
  check_range("length", o.length, 1, 1000000);
  if (o.goal != -1) check_range("goal", o.goal, 0, 3);
  check_range("goal_weight", o.goal_weight, -1000.0, 1000.0);
  check_range("intended", o.intended, 0.0, 1.0);
  check_range("discount", o.discount, 0.0, 0.999999);
  if (o.confounders != -1) check_range("confounders", o.confounders, 0, 64);
  check_range("per_step", o.per_step, 1, 10000);
  check_range("labeller_mass", o.labeller.mass, 0.0, 1.0);
  check_range("labeller_accuracy", o.labeller.accuracy, 0.0, 1.0);
  check_range("controlled", o.controlled, 1, 100000);
  // The demonstrations are held in memory: 10^8 steps is already ~2 GB of steps and their observations.
  if (static_cast<double>(o.trajectories) * o.length > 1e8)
    throw InputError("trajectories", "trajectories * length is more than 10^8 steps");
}

// The demonstrations watched by the paper's Gridworld sensor with |E| elements, eta from
// the labeller (its pick as each observation's context), the truth kept; a controlled run
// (the subject alone) as "controlled" trajectories; O learned with learned eta.
void watch_gridworld(const GridworldProblemOptions& o, const GridworldTask& task, Rng& rng, Problem& problem) {
  const int sources = 1 + o.confounders;
  const Eigen::MatrixXd subject_o = gridworld_subject_observation_model(o.size, 1.0);
  const Eigen::MatrixXd elements = random_confounder_observation_model(o.confounders, rng);
  GridworldObservationOptions options;
  options.confounders = o.confounders;
  options.per_step = o.per_step;
  GridworldObservations observed = observe_gridworld(task.mdp, task.trajectories, subject_o, elements, options, rng);
  assign_labeller_eta(observed, sources, o.labeller, rng);
  const std::vector<Trajectory> controlled =
      soft_expert_demonstration(task.mdp, task.true_weights, o.controlled, o.length, rng);
  options.confounders = 0;
  options.eta = EtaKind::kTrue;
  GridworldObservations alone = observe_gridworld(task.mdp, controlled, subject_o, Eigen::MatrixXd(0, 4), options, rng);
  for (size_t i = 0; i < controlled.size(); ++i) {
    DemonstratedTrajectory item;
    item.controlled = true;
    ObservedTrajectory steps = alone.trajectories[i];
    steps.eta = RowMatrix::Zero(steps.num_observations(), sources);
    steps.eta.col(0).setOnes();  // the subject alone
    steps.contexts.assign(static_cast<size_t>(steps.num_observations()), 0);
    item.steps = std::move(steps);
    item.truth = controlled[i];
    problem.demonstration.push_back(std::move(item));
  }
  for (size_t i = 0; i < task.trajectories.size(); ++i) {
    DemonstratedTrajectory item;
    item.steps = observed.trajectories[i];
    item.truth = task.trajectories[i];
    problem.demonstration.push_back(std::move(item));
  }
  ObservationPrior prior;
  prior.num_symbols = 4;
  prior.num_confounders = o.confounders;
  prior.subject_alpha = Eigen::MatrixXd::Ones(task.mdp.num_pairs(), 4);  // replaced by the controlled run's
  prior.confounder_alpha = Eigen::MatrixXd::Ones(o.confounders, 4);
  problem.observation_model = prior;
}

}  // namespace

Problem gridworld_problem(const GridworldProblemOptions& o) {
  check(o);
  GridworldOptions options;
  options.size = o.size;
  options.intended = o.intended;
  options.discount = o.discount;
  Rng rng(o.seed);
  GridworldTask task = make_gridworld_task(options, o.trajectories, o.length, rng);
  if ((o.goal >= 0 && o.goal != task.goal) || o.goal_weight != 1.0) {
    if (o.goal >= 0) task.goal = o.goal;
    task.true_weights.setZero();
    task.true_weights[task.goal] = o.goal_weight;
    task.trajectories = soft_expert_demonstration(task.mdp, task.true_weights, o.trajectories, o.length, rng);
  }
  Problem problem;
  problem.mdp = task.mdp;
  problem.state_names = gridworld_state_names(o.size);
  problem.action_names = gridworld_action_names();
  problem.feature_names = gridworld_feature_names();
  if (o.confounders >= 0) {
    watch_gridworld(o, task, rng, problem);
  } else {
    for (auto& trajectory : task.trajectories) {
      DemonstratedTrajectory item;
      item.truth = std::move(trajectory);
      problem.demonstration.push_back(std::move(item));
    }
  }
  problem.true_weights = task.true_weights;
  return problem;
}

}  // namespace hbirl
