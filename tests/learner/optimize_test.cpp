#include "learner/optimize.hpp"

#include <gtest/gtest.h>

namespace hbirl {
namespace {

// A concave quadratic with its maximum at c: J(x) = -1/2 (x - c)^T H (x - c).
Objective quadratic(const Eigen::VectorXd& c, const Eigen::MatrixXd& h) {
  return [c, h](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    const Eigen::VectorXd d = x - c;
    g = -h * d;
    return -0.5 * d.dot(h * d);
  };
}

TEST(Optimize, LbfgsFindsTheMaximum) {
  Eigen::MatrixXd h(3, 3);
  h << 4, 1, 0, 1, 3, 0.5, 0, 0.5, 2;
  const Eigen::Vector3d c(1.0, -2.0, 0.5);
  const OptimizeResult r = maximize_lbfgs(quadratic(c, h), Eigen::Vector3d::Zero(), {});
  EXPECT_TRUE(r.converged) << r.status;
  EXPECT_LT((r.x - c).norm(), 1e-7);
  EXPECT_GT(r.evaluations, 1);
}

TEST(Optimize, ExponentiatedGradientFindsTheMaximumInsideTheBall) {
  Eigen::MatrixXd h(3, 3);
  h << 4, 1, 0, 1, 3, 0.5, 0, 0.5, 2;
  const Eigen::Vector3d c(1.0, -2.0, 0.5);
  OptimizerOptions options;
  options.kind = OptimizerKind::kExponentiatedGradient;
  options.max_iterations = 20000;
  options.eg_radius = 10.0;
  const OptimizeResult r = maximize(quadratic(c, h), Eigen::Vector3d(0.3, 0.3, 0.3), options);
  EXPECT_LT((r.x - c).norm(), 1e-5) << r.status << " after " << r.iterations;
}

// With the optimum outside the L1 ball, EG ends on the boundary, as close as it can get.
TEST(Optimize, ExponentiatedGradientStaysInTheBall) {
  const Eigen::Vector2d c(5.0, 5.0);
  OptimizerOptions options;
  options.kind = OptimizerKind::kExponentiatedGradient;
  options.eg_radius = 2.0;
  options.max_iterations = 5000;
  const OptimizeResult r = maximize(quadratic(c, Eigen::Matrix2d::Identity()), Eigen::Vector2d::Zero(), options);
  EXPECT_LE(r.x.lpNorm<1>(), 2.0 + 1e-12);
  EXPECT_NEAR(r.x[0], 1.0, 1e-3);
  EXPECT_NEAR(r.x[1], 1.0, 1e-3);
}

}  // namespace
}  // namespace hbirl
