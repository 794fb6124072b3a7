#include "learner/mcmc_diagnostics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

#include "learner/rng.hpp"

namespace hbirl {
namespace {

// A standard normal draw (Box-Muller).
double normal(Rng& rng) {
  const double u = 1.0 - rng.uniform();  // (0, 1]
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::acos(-1.0) * rng.uniform());
}

Chains iid_normal(int chains, int draws, Rng& rng) {
  Chains out(static_cast<size_t>(chains), std::vector<double>(static_cast<size_t>(draws)));
  for (auto& chain : out) {
    for (double& x : chain) x = normal(rng);
  }
  return out;
}

// Stationary AR(1): x_t = rho x_{t-1} + sqrt(1 - rho^2) e_t, x_0 ~ N(0, 1).
Chains ar1(int chains, int draws, double rho, Rng& rng) {
  Chains out = iid_normal(chains, draws, rng);
  for (auto& chain : out) {
    for (size_t t = 1; t < chain.size(); ++t) chain[t] = rho * chain[t - 1] + std::sqrt(1.0 - rho * rho) * chain[t];
  }
  return out;
}

TEST(McmcDiagnostics, NormalQuantileKnownValues) {
  // Reference values: Python's statistics.NormalDist().inv_cdf.
  EXPECT_EQ(normal_quantile(0.5), 0.0);
  EXPECT_NEAR(normal_quantile(0.975), 1.9599639845400536, 1e-14);
  EXPECT_NEAR(normal_quantile(0.025), -1.9599639845400538, 1e-14);
  EXPECT_NEAR(normal_quantile(0.8413447460685429), 1.0, 1e-14);  // Phi(1)
  EXPECT_NEAR(normal_quantile(0.001), -3.090232306167813, 1e-13);
  EXPECT_NEAR(normal_quantile(1e-10), -6.361340902404056, 1e-12);
  EXPECT_NEAR(normal_quantile(0.18), -0.9153650878428141, 1e-14);
  EXPECT_THROW(normal_quantile(0.0), std::invalid_argument);
  EXPECT_THROW(normal_quantile(1.0), std::invalid_argument);
}

// Pooled draws 0 0 1 1 1 2 (S = 6): ranks 1.5 for the 0s, 4 for the 1s, 6 for the 2, so
// z = Phi^-1((r - 3/8) / 6.25) = Phi^-1(0.18), Phi^-1(0.58), Phi^-1(0.9).
TEST(McmcDiagnostics, RankNormaliseAveragesTies) {
  const Chains z = rank_normalise({{0.0, 1.0, 1.0}, {2.0, 1.0, 0.0}});
  const double zero = -0.9153650878428141;
  const double one = 0.20189347914185077;
  const double two = 1.2815515655446008;
  const Chains expected{{zero, one, one}, {two, one, zero}};
  for (size_t c = 0; c < 2; ++c) {
    for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(z[c][i], expected[c][i], 1e-14) << c << " " << i;
  }
}

TEST(McmcDiagnostics, SplitDropsTheMiddleOfOddChains) {
  const Chains split = split_chains({{1, 2, 3, 4, 5}, {6, 7, 8, 9, 10}});
  EXPECT_EQ(split, (Chains{{1, 2}, {4, 5}, {6, 7}, {9, 10}}));
}

// By hand: chains (1 3 2 6) and (4 4 5 9) split into (1 3) (2 6) (4 4) (5 9), N = 2, M = 4.
// Means 2, 4, 4, 7 (grand mean 4.25); variances 2, 8, 0, 8, so W = 4.5;
// B/N = (2.25^2 + 0.25^2 + 0.25^2 + 2.75^2) / 3 = 12.75 / 3 = 4.25;
// var+ = (N-1)/N W + B/N = 2.25 + 4.25 = 6.5; R-hat = sqrt(6.5 / 4.5) = sqrt(13) / 3.
TEST(McmcDiagnostics, SplitRhatByHand) {
  EXPECT_NEAR(split_rhat({{1, 3, 2, 6}, {4, 4, 5, 9}}), std::sqrt(13.0) / 3.0, 1e-15);
  // Odd chains: the middle draws (here wild) are dropped, the same number.
  EXPECT_NEAR(split_rhat({{1, 3, 100, 2, 6}, {4, 4, -100, 5, 9}}), std::sqrt(13.0) / 3.0, 1e-15);
}

// Independent draws: R-hat ~ 1 and ESS ~ S. The ESS estimate itself is noisy: over 400
// seeds of 4 x 1000 iid draws it had a standard deviation of 4.5% of S (range -18% to
// +9%), so each run must be within 20% and the mean of 10 runs within 5% (> 3 standard
// errors).
void expect_independent(const std::function<Chains(Rng&)>& draw) {
  double total = 0.0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    Rng rng(seed);
    const Chains x = draw(rng);
    EXPECT_NEAR(rank_normalised_split_rhat(x), 1.0, 0.01) << seed;
    const double ess = bulk_ess(x);
    EXPECT_NEAR(ess, 4000.0, 0.20 * 4000.0) << seed;
    total += ess;
    const std::optional<QuantityDiagnostics> q = diagnose(x);
    ASSERT_TRUE(q.has_value());
    EXPECT_EQ(q->rhat, rank_normalised_split_rhat(x));
    EXPECT_EQ(q->bulk_ess, ess);
  }
  EXPECT_NEAR(total / 10.0, 4000.0, 0.05 * 4000.0);
}

TEST(McmcDiagnostics, IndependentNormalDrawsLookConverged) {
  expect_independent([](Rng& rng) { return iid_normal(4, 1000, rng); });
}

// Indicators: almost all draws tie. Rank normalisation of two-valued draws is an affine
// map, and R-hat and ESS are invariant under affine maps, so the rank-normalised numbers
// equal the plain ones of the split indicators.
TEST(McmcDiagnostics, IndependentIndicatorsLookConverged) {
  const auto bernoulli = [](Rng& rng) {
    Chains x(4, std::vector<double>(1000));
    for (auto& chain : x) {
      for (double& v : chain) v = rng.uniform() < 0.3 ? 1.0 : 0.0;
    }
    return x;
  };
  expect_independent(bernoulli);
  Rng rng(1);
  const Chains x = bernoulli(rng);
  EXPECT_NEAR(rank_normalised_split_rhat(x), split_rhat(x), 1e-12);
  EXPECT_NEAR(bulk_ess(x), effective_sample_size(split_chains(x)), 1e-9 * 4000.0);
}

// AR(1) with rho = 0.9: tau = (1 + rho) / (1 - rho) = 19, so ESS = S / 19. 4 x 25000 draws
// give ESS ~ 5263 with a standard error of a few per cent; 10% is > 3 of them.
TEST(McmcDiagnostics, Ar1EssMatchesTheory) {
  const double rho = 0.9;
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    Rng rng(seed);
    const Chains x = ar1(4, 25000, rho, rng);
    const double expected = 100000.0 * (1.0 - rho) / (1.0 + rho);
    EXPECT_NEAR(bulk_ess(x), expected, 0.10 * expected) << seed;
    EXPECT_NEAR(effective_sample_size(x), expected, 0.10 * expected) << seed;
    EXPECT_LT(rank_normalised_split_rhat(x), 1.01) << seed;
  }
}

// Two chains around 0 and two around 5 never meet: R-hat far above 1 (rank normalisation
// bounds it: for two separated halves it is about 1 / sqrt(1 - 2/pi) ~ 1.66).
TEST(McmcDiagnostics, ChainsStuckInDifferentModes) {
  Rng rng(3);
  Chains x = iid_normal(4, 500, rng);
  for (double& v : x[2]) v += 5.0;
  for (double& v : x[3]) v += 5.0;
  EXPECT_GT(rank_normalised_split_rhat(x), 1.5);
  EXPECT_GT(split_rhat(x), 2.0);
  EXPECT_LT(bulk_ess(x), 100.0);
}

// Same location, different scale: the rank-normalised draws agree on average (their
// split-R-hat is ~1), the folded ones (|x - median|) do not.
TEST(McmcDiagnostics, FoldingCatchesChainsThatDifferInScale) {
  Rng rng(4);
  Chains x = iid_normal(2, 2000, rng);
  for (double& v : x[1]) v *= 3.0;
  const double bulk_only = potential_scale_reduction(rank_normalise(split_chains(x)));
  EXPECT_LT(bulk_only, 1.01);
  EXPECT_GT(rank_normalised_split_rhat(x), 1.1);
}

TEST(McmcDiagnostics, IdenticalDrawsAreSkipped) {
  const Chains same(4, std::vector<double>(100, 1.0));
  EXPECT_FALSE(diagnose(same).has_value());
  EXPECT_TRUE(std::isnan(potential_scale_reduction(same)));
  // Constant within the chains used (after the split), different between: never mixed.
  Chains stuck(2, std::vector<double>(100, 0.0));
  stuck[1].assign(100, 1.0);
  ASSERT_TRUE(diagnose(stuck).has_value());
  EXPECT_TRUE(std::isinf(diagnose(stuck)->rhat));
  EXPECT_LT(diagnose(stuck)->bulk_ess, 400.0);
  // Too short to split into halves of two.
  EXPECT_FALSE(diagnose({{0, 1, 0}, {1, 0, 1}}).has_value());
}

TEST(McmcDiagnostics, RejectsRaggedOrNonFiniteChains) {
  EXPECT_THROW(split_rhat({{1, 2, 3, 4}, {1, 2, 3}}), std::invalid_argument);
  EXPECT_THROW(rank_normalise({{1, NAN}}), std::invalid_argument);
  EXPECT_THROW(diagnose({{1, 2, 3, INFINITY}, {1, 2, 3, 4}}), std::invalid_argument);
  std::vector<double> many(40);
  for (size_t i = 0; i < many.size(); ++i) many[i] = static_cast<double>(i);  // > 16 distinct: sorted
  many.back() = NAN;
  EXPECT_THROW(rank_normalise({many}), std::invalid_argument);
}

// Merging takes max / min / sum: any order gives the same bits; the default checks nothing.
TEST(McmcDiagnostics, MergeIsOrderFree) {
  McmcDiagnostics a;
  a.chains = 4;
  a.add({1.02, 350.0});
  a.add({1.001, 900.0});
  McmcDiagnostics b;
  b.chains = 4;
  b.add({1.005, 120.0});
  McmcDiagnostics ab = a;
  ab += b;
  McmcDiagnostics ba = b;
  ba += a;
  EXPECT_EQ(ab.worst_rhat, 1.02);
  EXPECT_EQ(ab.worst_bulk_ess, 120.0);
  EXPECT_EQ(ab.quantities, 3);
  EXPECT_EQ(ba.worst_rhat, ab.worst_rhat);
  EXPECT_EQ(ba.worst_bulk_ess, ab.worst_bulk_ess);
  EXPECT_EQ(ba.quantities, ab.quantities);
  EXPECT_FALSE(ab.converged());
  McmcDiagnostics neutral;
  EXPECT_TRUE(neutral.converged());
  neutral += ab;
  EXPECT_EQ(neutral.worst_rhat, ab.worst_rhat);
  EXPECT_EQ(neutral.chains, 4);
}

}  // namespace
}  // namespace hbirl
