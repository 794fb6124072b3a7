#include "experiments/gridworld_scenario.hpp"

namespace hbirl {

GridworldScenario make_gridworld_scenario(const GridworldScenarioOptions& o, int run, int confounders) {
  const Rng root(o.seed);
  Rng task_rng = root.split(static_cast<std::uint64_t>(run));
  GridworldOptions grid;
  grid.size = o.size;
  GridworldScenario s{make_gridworld_task(grid, o.trajectories, o.length, task_rng), {}, {}, {}, {}};
  s.subject_o = gridworld_subject_observation_model(o.size, 1.0);
  const std::vector<Trajectory> controlled =
      soft_expert_demonstration(s.task.mdp, s.task.true_weights, o.trajectories, o.length, task_rng);
  s.controlled_alpha = controlled_run_alpha(s.task.mdp, controlled, s.subject_o, o.per_step, 1.0, task_rng);
  Rng obs_rng = task_rng.split(1000 + static_cast<std::uint64_t>(confounders));
  s.confounder_o = random_confounder_observation_model(confounders, obs_rng);
  GridworldObservationOptions observe;
  observe.confounders = confounders;
  observe.per_step = o.per_step;
  observe.eta = EtaKind::kUniform;
  s.observations = observe_gridworld(s.task.mdp, s.task.trajectories, s.subject_o, s.confounder_o, observe, obs_rng);
  return s;
}

namespace {

// Sums `right(posterior source row, true source)` over every observation. Identical
// observations of a step have the same source posterior: it is computed once per
// distinct one (as the E-step does), and each observation is scored against its own truth.
template <typename Right>
double share_right(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                   const std::vector<ObservedTrajectory>& trajectories,
                   const std::vector<std::vector<int>>& true_sources, Right right) {
  ExactEngine engine(mdp);
  long long hits = 0;
  long long total = 0;
  for (size_t i = 0; i < trajectories.size(); ++i) {
    std::vector<int> merged_of;
    const ObservedTrajectory merged = merge_identical_observations(trajectories[i], &merged_of);
    const TrajectoryPosterior post = engine.posterior(policy, model, merged);
    for (size_t n = 0; n < merged_of.size(); ++n) {
      hits += right(post.sources.row(merged_of[n]), true_sources[i][n]) ? 1 : 0;
      ++total;
    }
  }
  return total == 0 ? -1.0 : static_cast<double>(hits) / static_cast<double>(total);
}

}  // namespace

double source_accuracy(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                       const GridworldObservations& observations) {
  return share_right(mdp, policy, model, observations.trajectories, observations.true_sources,
                     [](const auto& sources, int truth) {
                       Eigen::Index best = 0;
                       sources.maxCoeff(&best);
                       return best == truth;
                     });
}

double subject_label_accuracy(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                              const std::vector<ObservedTrajectory>& trajectories,
                              const std::vector<std::vector<int>>& true_sources) {
  return share_right(mdp, policy, model, trajectories, true_sources,
                     [](const auto& sources, int truth) { return (sources(0) > 0.5) == (truth == 0); });
}

}  // namespace hbirl
