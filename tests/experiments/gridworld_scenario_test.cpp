#include "experiments/gridworld_scenario.hpp"

#include <gtest/gtest.h>

#include "learner/soft_value_iteration.hpp"

namespace hbirl {
namespace {

// The score of every observation against its own posterior source row, each raw
// observation's posterior computed on the raw trajectory: what source_accuracy computes
// once per distinct observation of a step.
double raw_source_accuracy(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                           const GridworldObservations& observations) {
  ExactEngine engine(mdp);
  long long hits = 0;
  long long total = 0;
  for (size_t i = 0; i < observations.trajectories.size(); ++i) {
    const TrajectoryPosterior post = engine.posterior(policy, model, observations.trajectories[i]);
    for (Eigen::Index n = 0; n < post.sources.rows(); ++n) {
      Eigen::Index best = 0;
      post.sources.row(n).maxCoeff(&best);
      hits += best == observations.true_sources[i][static_cast<size_t>(n)] ? 1 : 0;
      ++total;
    }
  }
  return static_cast<double>(hits) / static_cast<double>(total);
}

TEST(GridworldScenario, SourceAccuracyScoresEveryObservation) {
  GridworldScenarioOptions o;
  o.trajectories = 4;
  o.per_step = 12;
  for (int confounders : {1, 3}) {
    for (EtaKind kind : {EtaKind::kUniform, EtaKind::kPlausible}) {
      GridworldScenario s = make_gridworld_scenario(o, 0, confounders);
      Rng rng(5);
      assign_eta(s.observations, 1 + confounders, kind, rng);
      const SoftSolution policy = soft_value_iteration(s.task.mdp, s.task.mdp.reward(s.task.true_weights));
      const ObservationModel model{s.subject_o, s.confounder_o, {}};
      const double merged = source_accuracy(s.task.mdp, policy, model, s.observations);
      EXPECT_EQ(merged, raw_source_accuracy(s.task.mdp, policy, model, s.observations)) << confounders;
      EXPECT_GT(merged, 0.0);
      EXPECT_LT(merged, 1.0);
    }
  }
}

}  // namespace
}  // namespace hbirl
