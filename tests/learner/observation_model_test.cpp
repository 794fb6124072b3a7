#include "learner/observation_model.hpp"

#include <gtest/gtest.h>

namespace hbirl {
namespace {

TEST(ObservationModel, DirichletMean) {
  Eigen::MatrixXd alpha(2, 3);
  alpha << 1, 2, 7, 0, 0, 0;
  const Eigen::MatrixXd mean = dirichlet_mean(alpha);
  EXPECT_DOUBLE_EQ(mean(0, 0), 0.1);
  EXPECT_DOUBLE_EQ(mean(0, 2), 0.7);
  EXPECT_DOUBLE_EQ(mean(1, 1), 1.0 / 3);  // empty prior: uniform
}

// Hand-computed: alpha = (4, 6), alpha_dot = (10, 0), c = 0.25:
// alpha' = 0.25 (10, 0) + 0.75 (4, 6) = (5.5, 4.5); mean (0.55, 0.45).
TEST(ObservationModel, AlphaUpdateByHand) {
  ObservationPrior prior;
  prior.num_symbols = 2;
  prior.num_confounders = 1;
  prior.subject_alpha = Eigen::MatrixXd(1, 2);
  prior.subject_alpha << 4, 6;
  prior.confounder_alpha = Eigen::MatrixXd(1, 2);
  prior.confounder_alpha << 1, 1;
  AlphaCounts dot = AlphaCounts::zero(1, 1, 2);
  dot.subject << 10, 0;
  dot.confounders << 2, 6;
  update_alpha(prior, dot, 0.25);
  EXPECT_DOUBLE_EQ(prior.subject_alpha(0, 0), 5.5);
  EXPECT_DOUBLE_EQ(prior.subject_alpha(0, 1), 4.5);
  EXPECT_DOUBLE_EQ(prior.confounder_alpha(0, 0), 1.25);
  EXPECT_DOUBLE_EQ(prior.confounder_alpha(0, 1), 2.25);
  const ObservationModel model = dirichlet_mean(prior);
  EXPECT_DOUBLE_EQ(model.subject(0, 0), 0.55);
  EXPECT_DOUBLE_EQ(model.confounders(0, 1), 2.25 / 3.5);
}

}  // namespace
}  // namespace hbirl
