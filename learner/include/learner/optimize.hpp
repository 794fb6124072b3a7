#pragma once
// Maximisers for the M-step. Both take an objective that returns J(x) and fills its
// gradient, and both return the best point they evaluated.
#include <Eigen/Core>
#include <functional>
#include <string>

namespace hbirl {

using Objective = std::function<double(const Eigen::VectorXd& x, Eigen::VectorXd& gradient)>;

enum class OptimizerKind {
  kLbfgs,                  // L-BFGS (Debian's liblbfgs) with More-Thuente line search. Default.
  kExponentiatedGradient,  // the paper's adaptive optimistic EG (Steinhardt & Liang 2014)
};

struct OptimizerOptions {
  OptimizerKind kind = OptimizerKind::kLbfgs;
  int max_iterations = 1000;
  // Converged when ||gradient||_2 <= gradient_tolerance * max(1, ||x||_2). L-BFGS also
  // counts a line search that can no longer improve the objective in double precision
  // as converged when ||gradient||_2 <= 1e-6 * max(1, ||x||_2) ("working precision").
  double gradient_tolerance = 1e-9;
  // EG works on the L1 ball ||x||_1 <= eg_radius (x = radius * (w+ - w-), w on the
  // simplex of 2K experts); a solution on the boundary means the radius was too small.
  double eg_radius = 50.0;
  double eg_learning_rate = 0.25;  // eta; the regret bound needs eta <= 1/4
};

struct OptimizeResult {
  Eigen::VectorXd x;
  double value = 0.0;
  double gradient_norm = 0.0;
  int iterations = 0;
  int evaluations = 0;
  bool converged = false;
  std::string status;
};

OptimizeResult maximize_lbfgs(const Objective& f, Eigen::VectorXd x0, const OptimizerOptions& options);

// Adaptive optimistic exponentiated gradient (Steinhardt & Liang 2014, Alg. 2 with the
// path-length hint m_t = z_{t-1}): over 2K experts (each feature's positive and
// negative part),
//   w_t ∝ exp(beta_t - eta m_t),   beta_{t+1} = beta_t - eta z_t - eta^2 (z_t - m_t)^2,
// with losses z = -d J / d w scaled into [-1, 1] by the largest gradient seen so far.
OptimizeResult maximize_exponentiated_gradient(const Objective& f, Eigen::VectorXd x0, const OptimizerOptions& options);

OptimizeResult maximize(const Objective& f, Eigen::VectorXd x0, const OptimizerOptions& options);

const char* to_string(OptimizerKind kind);

}  // namespace hbirl
