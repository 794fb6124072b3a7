#include "learner/estep_exact.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tiny_observed_problem.hpp"

namespace hbirl {
namespace {

// Sums the joint Pr(X, Z, observations) over every trajectory X of pairs and every
// labelling Z of the observations.
struct BruteForce {
  double likelihood = 0.0;
  RowMatrix marginals;
  RowMatrix sources;
  EStepStatistics stats;
};

BruteForce brute_force(const testing::TinyProblem& p) {
  const Mdp& mdp = p.mdp;
  const ObservedTrajectory& tr = p.trajectory;
  const int T = tr.length();
  const int P = mdp.num_pairs();
  const int N = tr.num_observations();
  const int Z = 1 + p.model.num_confounders();
  BruteForce out;
  out.marginals = RowMatrix::Zero(T, P);
  out.sources = RowMatrix::Zero(N, Z);
  out.stats = EStepStatistics::zero(P, p.model.num_confounders(), p.model.num_symbols());
  std::vector<int> step_of(static_cast<size_t>(N));
  for (int t = 0; t < T; ++t) {
    for (int n = tr.step_begin[static_cast<size_t>(t)]; n < tr.step_begin[static_cast<size_t>(t) + 1]; ++n) {
      step_of[static_cast<size_t>(n)] = t;
    }
  }
  int sequences = 1;
  for (int t = 0; t < T; ++t) sequences *= P;
  int labelings = 1;
  for (int n = 0; n < N; ++n) labelings *= Z;
  std::vector<int> pairs(static_cast<size_t>(T));
  std::vector<int> labels(static_cast<size_t>(N));
  for (int code = 0; code < sequences; ++code) {
    int c = code;
    for (int t = 0; t < T; ++t, c /= P) pairs[static_cast<size_t>(t)] = c % P;
    double prior = 1.0;
    for (int t = 0; t < T && prior > 0.0; ++t) {
      const int r = pairs[static_cast<size_t>(t)];
      const int s = r / mdp.num_actions;
      if (mdp.is_terminal(s)) prior = 0.0;
      prior *= (t == 0 ? mdp.start[s] : mdp.transitions.coeff(pairs[static_cast<size_t>(t) - 1], s)) * p.policy.policy[r];
    }
    if (prior > 0.0 && tr.ends_in_terminal) {
      double exit = 0.0;
      for (int s2 = 0; s2 < mdp.num_states; ++s2) {
        if (mdp.is_terminal(s2)) exit += mdp.transitions.coeff(pairs[static_cast<size_t>(T) - 1], s2);
      }
      prior *= exit;
    }
    if (prior == 0.0) continue;
    for (int lc = 0; lc < labelings; ++lc) {
      int l = lc;
      for (int n = 0; n < N; ++n, l /= Z) labels[static_cast<size_t>(n)] = l % Z;
      double joint = prior;
      for (int n = 0; n < N; ++n) {
        const int z = labels[static_cast<size_t>(n)];
        const int w = tr.symbols[static_cast<size_t>(n)];
        const int r = pairs[static_cast<size_t>(step_of[static_cast<size_t>(n)])];
        joint *= tr.eta(n, z) * (z == 0 ? p.model.subject(r, w) : p.model.confounders(z - 1, w));
      }
      out.likelihood += joint;
      for (int t = 0; t < T; ++t) out.marginals(t, pairs[static_cast<size_t>(t)]) += joint;
      for (int n = 0; n < N; ++n) {
        const int z = labels[static_cast<size_t>(n)];
        const int w = tr.symbols[static_cast<size_t>(n)];
        out.sources(n, z) += joint;
        if (z == 0) {
          out.stats.alpha_dot.subject(pairs[static_cast<size_t>(step_of[static_cast<size_t>(n)])], w) += joint;
        } else {
          out.stats.alpha_dot.confounders(z - 1, w) += joint;
        }
      }
    }
  }
  out.marginals /= out.likelihood;
  out.sources /= out.likelihood;
  out.stats.alpha_dot.subject /= out.likelihood;
  out.stats.alpha_dot.confounders /= out.likelihood;
  out.stats.counts = out.marginals.colwise().sum().transpose();
  out.stats.log_likelihood = std::log(out.likelihood);
  return out;
}

TEST(ExactEngine, EqualsBruteForceEnumeration) {
  Rng rng(2024);
  int ends_tested = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    const BruteForce truth = brute_force(p);
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
