#include "learner/estep_mcmc.hpp"

#include <gtest/gtest.h>

#include "learner/estep_observations.hpp"
#include "tiny_observed_problem.hpp"

namespace hbirl {
namespace {

McmcOptions sweeps(int samples, int burn_in, int chains) {
  McmcOptions options;
  options.samples = samples;
  options.burn_in = burn_in;
  options.chains = chains;
  return options;
}

bool possible(const testing::TinyProblem& p) {
  return std::isfinite(ExactEngine(p.mdp).posterior(p.policy, p.model, p.trajectory).log_likelihood);
}

// The tiny MDPs have 2 successors per (s, a) out of 3 states: single-site moves alone
// can be reducible there, so stochastic ones (trial % 3 != 0) also get the block move.
McmcOptions::Block tiny_block(int trial) {
  return trial % 3 == 0 ? McmcOptions::Block::kAuto : McmcOptions::Block::kAlways;
}

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
  McmcOptions options = sweeps(20000, 1000, 2);
  int deterministic = 0;
  int ending = 0;
  for (int trial = 0; trial < 24; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    if (!possible(p)) continue;
    options.block = tiny_block(trial);
    const Agreement a = compare(p, options, 1000 + static_cast<std::uint64_t>(trial));
    EXPECT_LT(a.marginals, kTolerance) << "trial " << trial;
    EXPECT_LT(a.sources, kTolerance) << "trial " << trial;
    deterministic += trial % 3 == 0;
    ending += p.trajectory.ends_in_terminal;
  }
  EXPECT_GE(deterministic, 4);  // block moves exercised
  EXPECT_GE(ending, 1);
}

// With the terminal state entered seen (end_state), the paper's MCMC agrees with the exact
// engine too.
TEST(McmcEngine, AgreesWithExactWhenTheEndStateIsSeen) {
  Rng rng(99);
  McmcOptions options = sweeps(20000, 1000, 2);
  options.block = McmcOptions::Block::kAlways;
  int compared = 0, informative = 0;
  for (int trial = 0; trial < 8; ++trial) {
    testing::TinyProblem p = testing::two_exits(trial, rng);
    const RowMatrix unseen = ExactEngine(p.mdp).posterior(p.policy, p.model, p.trajectory).marginals;
    p.trajectory.end_state = 2 + trial % 2;
    if (!possible(p)) continue;
    // Where seeing the end moves the posterior by more than the tolerance, an engine that
    // ignored it would fail.
    const RowMatrix seen = ExactEngine(p.mdp).posterior(p.policy, p.model, p.trajectory).marginals;
    informative += (seen - unseen).cwiseAbs().maxCoeff() > 2 * kTolerance;
    const Agreement a = compare(p, options, 300 + static_cast<std::uint64_t>(trial));
    EXPECT_LT(a.marginals, kTolerance) << "trial " << trial;
    EXPECT_LT(a.sources, kTolerance) << "trial " << trial;
    ++compared;
  }
  EXPECT_GE(compared, 5);
  EXPECT_GE(informative, 2);
}

// With an end sensor's reports (end_symbols), the paper's MCMC agrees with the exact engine:
// the marginals, the sources and the end sensor's expected counts.
TEST(McmcEngine, AgreesWithExactOnAnEndSensorsReports) {
  Rng rng(515);
  McmcOptions options = sweeps(20000, 1000, 2);
  options.block = McmcOptions::Block::kAlways;
  int compared = 0, informative = 0;
  for (int trial = 0; trial < 8; ++trial) {
    testing::TinyProblem p = testing::two_exits(trial, rng);
    p.model.end = testing::random_distributions(p.mdp.num_states, 2, rng);
    const RowMatrix unreported = ExactEngine(p.mdp).posterior(p.policy, p.model, p.trajectory).marginals;
    p.trajectory.end_symbols = {trial % 2, trial % 2};
    if (!possible(p)) continue;
    const RowMatrix reported = ExactEngine(p.mdp).posterior(p.policy, p.model, p.trajectory).marginals;
    informative += (reported - unreported).cwiseAbs().maxCoeff() > 2 * kTolerance;
    const Agreement a = compare(p, options, 700 + static_cast<std::uint64_t>(trial));
    EXPECT_LT(a.marginals, kTolerance) << "trial " << trial;
    EXPECT_LT(a.sources, kTolerance) << "trial " << trial;
    McmcEngine mcmc(p.mdp, options);
    EStepStatistics sampled =
        EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
    EStepStatistics exact = sampled;
    Rng sampler(900 + static_cast<std::uint64_t>(trial));
    mcmc.accumulate(p.policy, p.model, p.trajectory, sampler, sampled);
    ExactEngine(p.mdp).accumulate(p.policy, p.model, p.trajectory, exact);
    ASSERT_EQ(sampled.alpha_dot.end.rows(), p.mdp.num_states);
    // Two reports: each entry is twice a probability, so twice the tolerance.
    EXPECT_LT((sampled.alpha_dot.end - exact.alpha_dot.end).cwiseAbs().maxCoeff(), 2 * kTolerance) << "trial " << trial;
    EXPECT_NEAR(sampled.alpha_dot.end.sum(), 2.0, 1e-9);
    ++compared;
  }
  EXPECT_GE(compared, 5);
  EXPECT_GE(informative, 2);
}

// The paper's single-site updates alone (no block move), where they are irreducible:
// every state reachable from every (s, a).
TEST(McmcEngine, SingleSiteUpdatesAloneAgreeOnDenseTransitions) {
  Rng rng(31);
  McmcOptions options = sweeps(20000, 1000, 2);
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

// The marginals the diagnostics check: those strictly between 0 and 1 (a pair never or
// always at a step has identical draws).
long long uncertain_marginals(const RowMatrix& marginals) {
  return ((marginals.array() > 0.0) && (marginals.array() < 1.0)).count();
}

// With enough draws the engine's chains pass the thresholds of Vehtari et al. 2021 on
// the tiny problems (where mixing takes a few sweeps), and every uncertain marginal is
// checked.
TEST(McmcEngine, DiagnosticsConvergedWithEnoughSamples) {
  Rng rng(77);
  McmcOptions options = sweeps(3000, 300, 4);
  long long checked = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    if (!possible(p)) continue;
    options.block = tiny_block(trial);
    McmcEngine mcmc(p.mdp, options);
    Rng sampler(500 + static_cast<std::uint64_t>(trial));
    const TrajectoryPosterior post = mcmc.posterior(p.policy, p.model, p.trajectory, sampler);
    EXPECT_EQ(post.mcmc.quantities, uncertain_marginals(post.marginals)) << trial;
    EXPECT_EQ(post.mcmc.chains, 4);
    if (post.mcmc.quantities == 0) continue;
    EXPECT_LE(post.mcmc.worst_rhat, 1.05) << trial;
    EXPECT_GT(post.mcmc.worst_bulk_ess, 500.0) << trial;  // the slowest mixing here gave ~1100
    checked += post.mcmc.quantities;
  }
  EXPECT_GE(checked, 20);
}

// 20 draws per chain cannot give a bulk ESS of 400: the warning threshold is crossed.
TEST(McmcEngine, DiagnosticsFlagTooFewSamples) {
  Rng rng(8);
  const testing::TinyProblem p = testing::tiny_problem(4, rng);
  McmcEngine mcmc(p.mdp, sweeps(20, 0, 4));
  Rng sampler(2);
  const TrajectoryPosterior post = mcmc.posterior(p.policy, p.model, p.trajectory, sampler);
  ASSERT_GT(post.mcmc.quantities, 0);
  EXPECT_LT(post.mcmc.worst_bulk_ess, kBulkEssThreshold);
  EXPECT_FALSE(post.mcmc.converged());
  // The exact engine reports nothing.
  EXPECT_EQ(ExactEngine(p.mdp).posterior(p.policy, p.model, p.trajectory).mcmc.quantities, 0);
}

// The diagnostics of a pass (40 trajectories: 3 blocks) are the worst over the
// trajectories, the same bits on 1 and 2 threads, and reach the E-step's result.
TEST(McmcEngine, DiagnosticsSameBitsWhateverTheThreadCount) {
  Rng rng(5);
  const testing::TinyProblem p = testing::tiny_problem(4, rng);
  ObservationPrior prior = testing::prior_at(p.model);  // its mean is the model
  prior.learn = false;
  McmcOptions mcmc = sweeps(200, 20, 4);
  mcmc.block = McmcOptions::Block::kAlways;
  std::vector<McmcDiagnostics> seen;
  for (int threads : {1, 2}) {
    ObservationEStepOptions options;
    options.engine = mcmc_engine_factory(mcmc);
    options.threads = threads;
    const ObservationEStep estep(p.mdp, std::vector<ObservedTrajectory>(40, p.trajectory), prior, options);
    seen.push_back(estep.statistics(p.policy, p.model, 11).mcmc);
    EStepState state = estep.initial_state(11);
    const EStepResult result = estep.expect(p.policy, state);
    EXPECT_GT(result.mcmc.quantities, 0);
    EXPECT_TRUE(std::isfinite(result.mcmc.worst_rhat));
  }
  ASSERT_GT(seen[0].quantities, 0);
  EXPECT_TRUE(std::isfinite(seen[0].worst_rhat) && std::isfinite(seen[0].worst_bulk_ess));
  EXPECT_EQ(seen[0].worst_rhat, seen[1].worst_rhat);
  EXPECT_EQ(seen[0].worst_bulk_ess, seen[1].worst_bulk_ess);
  EXPECT_EQ(seen[0].quantities, seen[1].quantities);
  EXPECT_EQ(seen[0].chains, 4);
}

}  // namespace
}  // namespace hbirl
