#include "learner/estep_exact.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "brute_force_posterior.hpp"
#include "tiny_observed_problem.hpp"

namespace hbirl {
namespace {

TEST(ExactEngine, EqualsBruteForceEnumeration) {
  Rng rng(2024);
  int ends_tested = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    const testing::BruteForce truth = testing::brute_force(p.mdp, p.policy, p.model, p.trajectory);
    if (p.trajectory.ends_in_terminal && truth.likelihood == 0.0) continue;  // no way out: skip
    ASSERT_GT(truth.likelihood, 0.0) << "trial " << trial;
    ends_tested += p.trajectory.ends_in_terminal;
    ExactEngine engine(p.mdp);
    const TrajectoryPosterior post = engine.posterior(p.policy, p.model, p.trajectory);
    EXPECT_NEAR(post.log_likelihood, std::log(truth.likelihood), 1e-9) << "trial " << trial;
    EXPECT_LT((post.marginals - truth.marginals).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    if (p.trajectory.num_observations() > 0) {
      EXPECT_LT((post.sources - truth.sources).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    }
    EStepStatistics stats = EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
    engine.accumulate(p.policy, p.model, p.trajectory, stats);
    EXPECT_NEAR(stats.log_likelihood, truth.stats.log_likelihood, 1e-9);
    EXPECT_LT((stats.counts - truth.stats.counts).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((stats.alpha_dot.subject - truth.stats.alpha_dot.subject).cwiseAbs().maxCoeff(), 1e-9);
    if (p.model.num_confounders() > 0) {
      EXPECT_LT((stats.alpha_dot.confounders - truth.stats.alpha_dot.confounders).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
  EXPECT_GE(ends_tested, 3);  // trajectories known to end in a terminal state were covered
}

// Thousands of observations per step and long trajectories: a direct product of the
// emissions would underflow; the log-space engine stays finite and normalised.
TEST(ExactEngine, ThousandsOfObservationsAndLongTrajectoriesDoNotUnderflow) {
  Rng rng(5);
  testing::TinyProblem p = testing::tiny_problem(0, rng);  // deterministic transitions
  const int length = 2000;
  const int per_step = 1000;
  ObservedTrajectory& tr = p.trajectory;
  tr = ObservedTrajectory{};
  const int Z = 1 + p.model.num_confounders();
  tr.eta = RowMatrix::Constant(static_cast<Eigen::Index>(length / 100) * per_step, Z, 1.0 / Z);
  for (int t = 0; t < length; ++t) {
    const int n = t % 100 == 0 ? per_step : 0;  // mostly occluded, some steps with 1000
    for (int i = 0; i < n; ++i) tr.symbols.push_back(rng.uniform_int(p.model.num_symbols()));
    tr.step_begin.push_back(static_cast<int>(tr.symbols.size()));
  }
  ExactEngine engine(p.mdp);
  const TrajectoryPosterior post = engine.posterior(p.policy, p.model, tr);
  EXPECT_TRUE(std::isfinite(post.log_likelihood));
  EXPECT_LT(post.log_likelihood, -1000.0);  // far below what a double product can hold
  for (int t = 0; t < length; t += 97) EXPECT_NEAR(post.marginals.row(t).sum(), 1.0, 1e-9) << t;
  for (int n = 0; n < tr.num_observations(); n += 333) EXPECT_NEAR(post.sources.row(n).sum(), 1.0, 1e-9);
}

TEST(ExactEngine, ImpossibleObservationsGiveMinusInfinity) {
  Rng rng(1);
  testing::TinyProblem p = testing::tiny_problem(1, rng);
  p.model.subject.col(0).setZero();
  p.model.subject.col(1).setOnes();  // symbol 0 can only come from... nobody
  p.model.confounders.col(0).setZero();
  p.trajectory = ObservedTrajectory{};
  p.trajectory.symbols = {0};
  p.trajectory.eta = RowMatrix::Constant(1, 1 + p.model.num_confounders(), 1.0 / (1 + p.model.num_confounders()));
  p.trajectory.step_begin = {0, 1};
  ExactEngine engine(p.mdp);
  EXPECT_EQ(engine.posterior(p.policy, p.model, p.trajectory).log_likelihood, -INFINITY);
  EStepStatistics stats = EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
  engine.accumulate(p.policy, p.model, p.trajectory, stats);
  EXPECT_EQ(stats.impossible, 1);
  EXPECT_EQ(stats.counts.sum(), 0.0);
}

}  // namespace
}  // namespace hbirl
