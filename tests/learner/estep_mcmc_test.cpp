#include "learner/estep_mcmc.hpp"

#include <gtest/gtest.h>

#include "tiny_observed_problem.hpp"

namespace hbirl {
namespace {

struct Agreement {
  double marginals = 0.0;  // max |MCMC - exact| over steps and pairs
  double sources = 0.0;    // max |MCMC - exact| over observations and sources
};

Agreement compare(const testing::TinyProblem& p, const McmcOptions& options, std::uint64_t seed) {
  ExactEngine exact(p.mdp);
  McmcEngine mcmc(p.mdp, options);
  Rng rng(seed);
  const TrajectoryPosterior e = exact.posterior(p.policy, p.model, p.trajectory);
  const TrajectoryPosterior m = mcmc.posterior(p.policy, p.model, p.trajectory, rng);
  EXPECT_DOUBLE_EQ(m.log_likelihood, e.log_likelihood);  // computed exactly in both
  Agreement a;
  a.marginals = (m.marginals - e.marginals).cwiseAbs().maxCoeff();
  if (p.trajectory.num_observations() > 0) a.sources = (m.sources - e.sources).cwiseAbs().maxCoeff();
  return a;
}

// Statistical tolerance: with 2 chains x 20000 sweeps, a probability estimate has a
// standard error below 0.5 / sqrt(40000 / tau); for the integrated autocorrelation times
// tau <= 20 seen on these problems that is <= 0.011, so 0.05 is > 4.5 standard errors.
constexpr double kTolerance = 0.05;

TEST(McmcEngine, AgreesWithExactOnRandomTinyProblems) {
  Rng rng(77);
  McmcOptions options;
  options.samples = 20000;
  options.burn_in = 1000;
  options.chains = 2;
  int deterministic = 0;
  int ending = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    if (!std::isfinite(ExactEngine(p.mdp).posterior(p.policy, p.model, p.trajectory).log_likelihood)) continue;
    // The tiny MDPs have 2 successors per (s, a) out of 3 states: single-site moves alone
    // can be reducible there, so stochastic ones also get the block move.
    options.block = trial % 3 == 0 ? McmcOptions::Block::kAuto : McmcOptions::Block::kAlways;
    const Agreement a = compare(p, options, 1000 + static_cast<std::uint64_t>(trial));
    EXPECT_LT(a.marginals, kTolerance) << "trial " << trial;
    EXPECT_LT(a.sources, kTolerance) << "trial " << trial;
    deterministic += trial % 3 == 0;
    ending += p.trajectory.ends_in_terminal;
  }
  EXPECT_GE(deterministic, 4);  // block moves exercised
  EXPECT_GE(ending, 1);
}

// The paper's single-site updates alone (no block move), where they are irreducible:
// every state reachable from every (s, a).
TEST(McmcEngine, SingleSiteUpdatesAloneAgreeOnDenseTransitions) {
  Rng rng(31);
  McmcOptions options;
  options.samples = 20000;
  options.burn_in = 1000;
  options.chains = 2;
  options.block = McmcOptions::Block::kNever;
  for (int trial = 0; trial < 6; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng, /*dense=*/true);
    const Agreement a = compare(p, options, 50 + static_cast<std::uint64_t>(trial));
    EXPECT_LT(a.marginals, kTolerance) << "trial " << trial;
    EXPECT_LT(a.sources, kTolerance) << "trial " << trial;
  }
}

// The estimates converge to the exact marginals as the number of samples grows.
TEST(McmcEngine, ErrorShrinksWithMoreSamples) {
  Rng rng(8);
  const testing::TinyProblem p = testing::tiny_problem(4, rng);
  McmcOptions few;
  few.samples = 200;
  McmcOptions many;
  many.samples = 50000;
  double error_few = 0.0;
  double error_many = 0.0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    error_few += compare(p, few, seed).marginals;
    error_many += compare(p, many, seed).marginals;
  }
  EXPECT_LT(error_many, 0.25 * error_few);
}

TEST(McmcEngine, AccumulateMatchesExactExpectations) {
  Rng rng(12);
  const testing::TinyProblem p = testing::tiny_problem(7, rng);
  McmcOptions options;
  options.samples = 40000;
  McmcEngine mcmc(p.mdp, options);
  ExactEngine exact(p.mdp);
  EStepStatistics a = EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
  EStepStatistics b = a;
  Rng sampler(3);
  mcmc.accumulate(p.policy, p.model, p.trajectory, sampler, a);
  exact.accumulate(p.policy, p.model, p.trajectory, b);
  EXPECT_DOUBLE_EQ(a.log_likelihood, b.log_likelihood);
  EXPECT_NEAR(a.counts.sum(), b.counts.sum(), 1e-9);
  EXPECT_LT((a.counts - b.counts).cwiseAbs().maxCoeff(), 3 * kTolerance);
  EXPECT_LT((a.alpha_dot.subject - b.alpha_dot.subject).cwiseAbs().maxCoeff(), 3 * kTolerance);
}

TEST(McmcEngine, SameSeedSameBits) {
  Rng rng(1);
  const testing::TinyProblem p = testing::tiny_problem(2, rng);
  McmcEngine mcmc(p.mdp, McmcOptions{});
  Rng a(5);
  Rng b(5);
  EXPECT_EQ(mcmc.posterior(p.policy, p.model, p.trajectory, a).marginals,
            mcmc.posterior(p.policy, p.model, p.trajectory, b).marginals);
}

}  // namespace
}  // namespace hbirl
