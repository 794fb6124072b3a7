#include "learner/mdp.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "learner/input_error.hpp"
#include "learner/rng.hpp"
#include "learner/trajectory.hpp"
#include "random_mdp.hpp"

namespace hbirl {
namespace {

Mdp two_state(double p01 = 1.0) {
  return make_mdp(2, 2, 1, {{0, 0, 0, 1.0}, {0, 1, 1, p01}, {1, 0, 0, 1.0}, {1, 1, 1, 1.0}}, {{1, 1, 0, 1.0}},
                  Eigen::Vector2d(1.0, 0.0), {}, 0.9);
}

std::string validation_error(const Mdp& mdp) {
  try {
    mdp.validate();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Mdp, ValidAndReward) {
  const Mdp mdp = two_state();
  EXPECT_EQ(validation_error(mdp), "");
  EXPECT_EQ(mdp.reward(Eigen::VectorXd::Constant(1, 2.0)), Eigen::Vector4d(0, 0, 0, 2));
  EXPECT_THROW(mdp.reward(Eigen::Vector2d(1, 1)), InputError);
}

TEST(Mdp, RejectsRowsNotSummingToOne) {
  EXPECT_NE(validation_error(two_state(0.9)).find("(s=0, a=1): probabilities sum to 0.9"), std::string::npos);
}

TEST(Mdp, RejectsNegativeAndNaNProbabilities) {
  Mdp mdp = make_mdp(1, 1, 0, {{0, 0, 0, 1.5}}, {}, Eigen::VectorXd::Ones(1), {}, 0.9);
  EXPECT_NE(validation_error(mdp).find("sum to 1.5"), std::string::npos);
  mdp = make_mdp(2, 1, 0, {{0, 0, 0, 1.5}, {0, 0, 1, -0.5}, {1, 0, 1, 1.0}}, {}, Eigen::Vector2d(1, 0), {}, 0.9);
  EXPECT_NE(validation_error(mdp).find("not a finite non-negative number"), std::string::npos);
  mdp = make_mdp(1, 1, 0, {{0, 0, 0, NAN}}, {}, Eigen::VectorXd::Ones(1), {}, 0.9);
  EXPECT_NE(validation_error(mdp).find("not a finite non-negative number"), std::string::npos);
}

TEST(Mdp, RejectsOutOfRangeIndices) {
  EXPECT_THROW(make_mdp(2, 1, 0, {{0, 0, 2, 1.0}}, {}, Eigen::Vector2d(1, 0), {}, 0.9), InputError);
  EXPECT_THROW(make_mdp(2, 1, 0, {{0, 1, 1, 1.0}}, {}, Eigen::Vector2d(1, 0), {}, 0.9), InputError);
  EXPECT_THROW(make_mdp(2, 1, 1, {}, {{0, 0, 1, 1.0}}, Eigen::Vector2d(1, 0), {}, 0.9), InputError);
  EXPECT_THROW(make_mdp(2, 1, 0, {}, {}, Eigen::Vector2d(1, 0), {5}, 0.9), InputError);
}

TEST(Mdp, RejectsBadStartDiscountAndDeadEnds) {
  Mdp mdp = two_state();
  mdp.start << 0.5, 0.4;
  EXPECT_NE(validation_error(mdp).find("mdp.start"), std::string::npos);
  mdp = two_state();
  mdp.discount = 1.0;
  EXPECT_NE(validation_error(mdp).find("mdp.discount"), std::string::npos);
  mdp = two_state();
  mdp.terminal[0] = 1;
  EXPECT_NE(validation_error(mdp).find("state 0 is terminal"), std::string::npos);
  // State 1 has no available action and is not terminal.
  mdp = make_mdp(2, 1, 0, {{0, 0, 1, 1.0}}, {}, Eigen::Vector2d(1, 0), {}, 0.9);
  EXPECT_NE(validation_error(mdp).find("state 1 is not terminal but has no available action"), std::string::npos);
  mdp = two_state();
  mdp.features(0, 0) = INFINITY;
  EXPECT_NE(validation_error(mdp).find("mdp.features"), std::string::npos);
}

}  // namespace
}  // namespace hbirl

namespace hbirl {

// probability_of_ending_within against sample_trajectory itself: on random MDPs with
// terminal states and a random policy, the exact probability of entering a terminal state
// within `length` steps agrees with the share of 20000 drawn trajectories that did, within
// 4.5 standard errors (a chance failure about once in 150000 runs per check).
TEST(Trajectories, TheProbabilityOfEndingWithinALengthIsTheSampledShare) {
  Rng rng(77);
  for (int trial = 0; trial < 6; ++trial) {
    testing::RandomMdpOptions o;
    o.states = 5 + trial;
    o.terminal = 1 + trial % 2;
    o.impossible = trial % 3 == 0;
    const Mdp mdp = testing::random_mdp(o, rng);
    Eigen::VectorXd policy = Eigen::VectorXd::Zero(mdp.num_pairs());
    for (int s = 0; s < mdp.num_states; ++s) {
      double sum = 0.0;
      for (int a = 0; a < mdp.num_actions; ++a) {
        if (mdp.available(s, a)) sum += policy[mdp.pair(s, a)] = 0.1 + rng.uniform();
      }
      for (int a = 0; a < mdp.num_actions; ++a) policy[mdp.pair(s, a)] /= sum > 0.0 ? sum : 1.0;
    }
    for (const int length : {1, 3, 8}) {
      const double exact = probability_of_ending_within(mdp, policy, length);
      constexpr int kDraws = 20000;
      int ended = 0;
      for (int k = 0; k < kDraws; ++k) {
        bool terminal = false;
        sample_trajectory(mdp, policy, length, rng, &terminal);
        ended += terminal;
      }
      const double share = static_cast<double>(ended) / kDraws;
      const double se = std::sqrt(std::max(exact * (1.0 - exact), 1e-6) / kDraws);
      EXPECT_NEAR(share, exact, 4.5 * se) << "trial " << trial << ", length " << length;
    }
    EXPECT_EQ(probability_of_ending_within(mdp, policy, 0), 0.0);
  }
}

}  // namespace hbirl
