#include "learner/rng.hpp"

#include <gtest/gtest.h>

namespace hbirl {
namespace {

TEST(Rng, SameSeedSameSequence) {
  Rng a(123);
  Rng b(123);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.next_u64(), b.next_u64());
  Rng c(124);
  EXPECT_NE(Rng(123).next_u64(), c.next_u64());
}

TEST(Rng, SplitDependsOnlyOnSeedAndStream) {
  Rng a(5);
  const Rng child_before = a.split(3);
  for (int i = 0; i < 10; ++i) a.next_u64();
  Rng x = child_before;
  Rng y = a.split(3);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(x.next_u64(), y.next_u64());
  EXPECT_NE(a.split(3).next_u64(), a.split(4).next_u64());
}

TEST(Rng, UniformRanges) {
  Rng rng(1);
  for (int i = 0; i < 10000; ++i) {
    const double u = rng.uniform();
    EXPECT_GE(u, 0.0);
    EXPECT_LT(u, 1.0);
    const int k = rng.uniform_int(7);
    EXPECT_GE(k, 0);
    EXPECT_LT(k, 7);
  }
  EXPECT_THROW(rng.uniform_int(0), std::invalid_argument);
}

// Frequencies of a categorical draw: chi-square with 3 degrees of freedom; the 1e-6
// quantile is 30.7, so a correct sampler fails this only by a one-in-a-million fluke
// (and the seed is fixed).
TEST(Rng, CategoricalFrequencies) {
  Rng rng(99);
  const Eigen::Vector4d w(1.0, 0.0, 2.0, 5.0);
  Eigen::Vector4d counts = Eigen::Vector4d::Zero();
  const int n = 80000;
  for (int i = 0; i < n; ++i) counts[rng.categorical(w)] += 1.0;
  EXPECT_EQ(counts[1], 0.0);
  double chi2 = 0.0;
  for (int i : {0, 2, 3}) {
    const double expected = n * w[i] / w.sum();
    chi2 += (counts[i] - expected) * (counts[i] - expected) / expected;
  }
  EXPECT_LT(chi2, 30.7);
  EXPECT_THROW(rng.categorical(Eigen::Vector2d::Zero()), std::invalid_argument);
}

}  // namespace
}  // namespace hbirl
