#include "learner/hidden_data_em.hpp"

#include <gtest/gtest.h>

#include <cstring>

#include "sim_driver/gridworld.hpp"

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
