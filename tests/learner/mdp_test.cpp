#include "learner/mdp.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "learner/input_error.hpp"

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
