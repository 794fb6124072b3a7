#include "learner/hidden_data_em.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "learner/estep_observations.hpp"
#include "sim_driver/gridworld/gridworld.hpp"
#include "sim_driver/file/random_task.hpp"

namespace hbirl {
namespace {

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

TEST(LearnReward, SameBitsWhateverTheThreadCount) {
  Rng rng(17);
  const GridworldTask task = make_gridworld_task({}, 20, 10, rng);
  const TruthEStep estep(task.mdp, task.trajectories);
  for (OptimizerKind kind : {OptimizerKind::kLbfgs, OptimizerKind::kExponentiatedGradient}) {
    LearnOptions options;
    options.optimizer.kind = kind;
    options.restarts = 5;
    options.seed = 3;
    options.threads = 1;
    const LearnResult one = learn_reward(task.mdp, estep, options);
    for (int threads : {2, 4, 8}) {
      options.threads = threads;
      const LearnResult many = learn_reward(task.mdp, estep, options);
      EXPECT_TRUE(same_bits(one.theta, many.theta)) << threads << " threads, " << to_string(kind);
      EXPECT_EQ(one.selected_restart, many.selected_restart);
      for (size_t r = 0; r < one.restarts.size(); ++r) {
        EXPECT_TRUE(same_bits(one.restarts[r].theta, many.restarts[r].theta));
      }
    }
  }
}

// EM's record (on_iteration) is non-decreasing to rounding on random tasks (traps, graphs,
// noisy sensors, 0-7 confounders), with and without SQUAREM, without a learned
// observation model, with it, with learned eta, and with an automatically chosen prior
// strength -- within each strength: a newly chosen strength is a new objective, and
// the record says so (ObservationPrior::strength of the reported alpha).
TEST(LearnReward, RecordedObjectiveNeverDecreasesOnRandomTasks) {
  enum class Alpha { kFixed, kLearned, kLearnedEta, kAutomatic };
  int checked = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    RandomTaskOverrides overrides;
    overrides.demonstrations = 6;
    const RandomTask task = make_random_task(seed, 0, overrides);
    for (Alpha mode : {Alpha::kFixed, Alpha::kLearned, Alpha::kLearnedEta, Alpha::kAutomatic}) {
      ObservationPrior prior = task.prior;
      prior.learn = mode != Alpha::kFixed;
      prior.learn_eta = mode == Alpha::kLearnedEta || mode == Alpha::kAutomatic;
      prior.automatic_strength = mode == Alpha::kAutomatic;
      const ObservationEStep estep(task.mdp, task.observed.trajectories, prior);
      for (bool accelerate : {false, true}) {
        LearnOptions options;
        options.accelerate = accelerate;
        options.threads = 1;
        options.max_em_iterations = 30;
        std::vector<std::pair<double, double>> record;  // (strength, objective)
        const IterationReport on_iteration = [&](int, int iteration, double objective, const Eigen::VectorXd&,
                                                 const EStepResult&, const ObservationPrior* alpha) {
          EXPECT_EQ(iteration, static_cast<int>(record.size()) + 1);
          record.emplace_back(alpha ? alpha->strength : 0.0, objective);
        };
        const LearnResult result = learn_reward(task.mdp, estep, options, on_iteration);
        const std::string where = "task " + std::to_string(seed) + ", mode " + std::to_string(static_cast<int>(mode)) +
                                  (accelerate ? ", SQUAREM" : ", plain EM");
        ASSERT_EQ(static_cast<int>(record.size()), result.restarts[0].em_iterations) << where;
        EXPECT_LE(result.restarts[0].em_iterations, result.restarts[0].em_evaluations) << where;
        for (size_t i = 1; i < record.size(); ++i) {
          if (record[i].first != record[i - 1].first) continue;  // a new strength: a new objective
          const double tolerance = 1e-8 * std::max(1.0, std::abs(record[i - 1].second));
          EXPECT_GE(record[i].second, record[i - 1].second - tolerance) << where << ", iterate " << i + 1;
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(LearnReward, RestartsAndSelectionRule) {
  Rng rng(2);
  const GridworldTask task = make_gridworld_task({}, 20, 10, rng);
  const TruthEStep estep(task.mdp, task.trajectories);
  LearnOptions options;
  options.restarts = 4;
  options.seed = 11;
  const LearnResult result = learn_reward(task.mdp, estep, options);
  ASSERT_EQ(result.restarts.size(), 4u);
  EXPECT_TRUE(result.restarts[0].initial_theta.isZero());
  for (size_t r = 1; r < 4; ++r) {
    EXPECT_FALSE(result.restarts[r].initial_theta.isZero());
    EXPECT_LE(result.restarts[r].initial_theta.lpNorm<Eigen::Infinity>(), 1.0);
  }
  // The selected restart has the highest score; with known trajectories the objective is
  // well behaved and every restart reaches the same optimum -- to ~1e-5 here, because the
  // weights of rarely visited corners have per-step curvature ~1e-4, so the rounding
  // noise of the objective leaves them that loose (their statistical error is far larger).
  for (const auto& r : result.restarts) {
    EXPECT_LE(r.score, result.restarts[static_cast<size_t>(result.selected_restart)].score);
    EXPECT_TRUE(r.converged) << r.optimizer_status;
    EXPECT_LT((r.theta - result.theta).lpNorm<Eigen::Infinity>(), 1e-4);
  }
  EXPECT_EQ(result.log_likelihood, result.restarts[static_cast<size_t>(result.selected_restart)].log_likelihood);
}

TEST(LearnReward, L2ShrinksTheWeights) {
  Rng rng(6);
  const GridworldTask task = make_gridworld_task({}, 20, 10, rng);
  const TruthEStep estep(task.mdp, task.trajectories);
  LearnOptions options;
  const double free_norm = learn_reward(task.mdp, estep, options).theta.norm();
  options.l2 = 0.05;
  const LearnResult shrunk = learn_reward(task.mdp, estep, options);
  EXPECT_LT(shrunk.theta.norm(), free_norm);
  EXPECT_LT(shrunk.restarts[0].score, shrunk.log_likelihood);
}

}  // namespace
}  // namespace hbirl
