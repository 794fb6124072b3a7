#include "learner/soft_value_iteration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hbirl {

namespace {
constexpr int kMaxNewtonSteps = 60;

// Below this relative Bellman residual a Newton step should square the residual; one that
// does not even halve it has met the floor of its own linear solve (PolicyMatrix accepts a
// solve at 1e-11 of |b| when BiCGSTAB stalls short of its tolerance: ~1e-13 of V at
// gamma = 0.99), and further steps only bounce there. Plain backups, a contraction, take
// over. 2.6 % of the Gridworld figure's solves used to bounce for all 60 Newton steps
// (docs/BENCHMARKS.md). At a discount near 1 the backups are slow; so is everything there
// (values in the thousands at gamma = 0.9999 took ~17,000 backups with or without this).
constexpr double kRoundingResidual = 1e-9;

bool newton_has_stalled(double residual, double previous) {
  return residual < kRoundingResidual && residual > 0.5 * previous;
}

// The relative residual to which a Newton step's linear system is solved, given the
// current relative Bellman residual r: r^2 between 1e-14 and 1e-2 (an inexact Newton
// method, Eisenstat & Walker 1996: far from the solution a rough step does as well, and
// the forcing term's decay keeps convergence superlinear). The solve ends, as before, only
// when a Bellman backup moves V by less than the tolerance.
double newton_tolerance(double r) { return std::clamp(r * r, PolicyMatrix::kWorkingTolerance, 1e-2); }
}  // namespace

SoftBellmanSolver::SoftBellmanSolver(const Mdp& mdp, SoftViOptions options)
    : mdp_(mdp), options_(options), policy_matrix_(mdp) {
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      if (mdp.is_terminal(s) || !mdp.available(s, a)) impossible_pairs_.push_back(mdp.pair(s, a));
    }
  }
  solution_.value = Eigen::VectorXd::Zero(mdp.num_states);
  solution_.q.resize(mdp.num_pairs());
  solution_.log_policy.resize(mdp.num_pairs());
  solution_.policy.resize(mdp.num_pairs());
  v_new_.resize(mdp.num_states);
}

void SoftBellmanSolver::backup(const Eigen::VectorXd& reward, const Eigen::VectorXd& v) {
  const int A = mdp_.num_actions;
  Eigen::VectorXd& q = solution_.q;
  q.noalias() = mdp_.transitions * v;
  q = reward + mdp_.discount * q;
  for (int r : impossible_pairs_) q[r] = kNegInf;
  for (int s = 0; s < mdp_.num_states; ++s) {
    if (mdp_.is_terminal(s)) {
      v_new_[s] = 0.0;
      continue;
    }
    const auto row = q.segment(static_cast<Eigen::Index>(s) * A, A);
    const double m = row.maxCoeff();
    v_new_[s] = m + std::log((row.array() - m).exp().sum());
  }
}

void SoftBellmanSolver::policy_from_q() {
  const int A = mdp_.num_actions;
  for (int s = 0; s < mdp_.num_states; ++s) {
    // q - v is finite for possible actions (v >= q), and exactly -inf otherwise.
    solution_.log_policy.segment(static_cast<Eigen::Index>(s) * A, A) =
        solution_.q.segment(static_cast<Eigen::Index>(s) * A, A).array() - v_new_[s];
  }
  solution_.policy = solution_.log_policy.array().exp();
  // Eigen's vectorised exp maps -inf to the smallest double, not to 0; impossible
  // actions must have probability exactly 0.
  for (int r : impossible_pairs_) {
    solution_.log_policy[r] = kNegInf;
    solution_.policy[r] = 0.0;
  }
}

const SoftSolution& SoftBellmanSolver::solve(const Eigen::VectorXd& reward) {
  SoftSolution& sol = solution_;
  Eigen::VectorXd v = has_solution_ ? sol.value : Eigen::VectorXd::Zero(mdp_.num_states);
  sol.iterations = 0;
  sol.newton_steps = 0;
  sol.converged = false;
  bool newton = options_.method == SoftViMethod::kNewton;
  Eigen::VectorXd b(mdp_.num_states);
  double previous_residual = std::numeric_limits<double>::infinity();  // relative, after the last Newton step
  for (;;) {
    backup(reward, v);
    ++sol.iterations;
    sol.residual = (v_new_ - v).lpNorm<Eigen::Infinity>();
    const double scale = std::max(1.0, v_new_.lpNorm<Eigen::Infinity>());
    if (!std::isfinite(sol.residual)) break;  // non-finite reward: leave converged = false
    if (sol.residual <= options_.tolerance * scale) {
      sol.converged = true;
      break;
    }
    if (sol.iterations >= options_.max_iterations) break;
    const double relative_residual = sol.residual / scale;
    if (newton && newton_has_stalled(relative_residual, previous_residual)) newton = false;
    previous_residual = relative_residual;
    if (newton && sol.newton_steps < kMaxNewtonSteps) {
      // Soft policy evaluation of the current soft policy:
      //   V = (I - gamma P_pi)^{-1} sum_a pi(a|s) (R(s,a) - log pi(a|s)).
      policy_from_q();
      const int A = mdp_.num_actions;
      for (int s = 0; s < mdp_.num_states; ++s) {
        double acc = 0.0;
        if (!mdp_.is_terminal(s)) {
          for (int a = 0; a < A; ++a) {
            const int r = s * A + a;
            if (sol.policy[r] > 0.0) acc += sol.policy[r] * (reward[r] - sol.log_policy[r]);
          }
        }
        b[s] = acc;
      }
      policy_matrix_.set_policy(sol.policy);
      Eigen::VectorXd x = v_new_;
      if (policy_matrix_.solve(b, x, newton_tolerance((v_new_ - v).norm() / std::max(1e-300, b.norm())))) {
        ++sol.newton_steps;
        v = x;
        continue;
      }
      newton = false;  // the iterative solve failed: finish with plain backups
    }
    v = v_new_;
  }
  policy_from_q();
  sol.value = v_new_;
  has_solution_ = sol.converged;
  policy_matrix_current_ = false;
  return sol;
}

void SoftBellmanSolver::warm_start(const Eigen::VectorXd& value) {
  if (value.size() != mdp_.num_states || !value.allFinite()) return;
  solution_.value = value;
  has_solution_ = true;
}

Eigen::VectorXd SoftBellmanSolver::solve_adjoint(const Eigen::VectorXd& rhs) {
  if (!policy_matrix_current_) {
    policy_matrix_.set_policy(solution_.policy);
    policy_matrix_current_ = true;
  }
  Eigen::VectorXd x = has_adjoint_ ? adjoint_ : rhs;
  if (!policy_matrix_.solve_transposed(rhs, x)) {
    // Fall back to the Neumann series x = sum_t (gamma P_pi^T)^t rhs, which converges
    // for gamma < 1; slow but certain.
    const SparseRowMatrix& m = policy_matrix_.matrix();
    x = rhs;
    for (int it = 0; it < options_.max_iterations; ++it) {
      // (I - gamma P^T) x = rhs  <=>  x = rhs + (I - M^T) x  with M = I - gamma P.
      Eigen::VectorXd next = rhs + x - m.transpose() * x;
      const double change = (next - x).lpNorm<Eigen::Infinity>();
      x.swap(next);
      if (change <= 1e-14 * std::max(1.0, x.lpNorm<Eigen::Infinity>())) break;
    }
  }
  has_adjoint_ = x.allFinite();
  if (has_adjoint_) adjoint_ = x;
  return x;
}

SoftSolution soft_value_iteration(const Mdp& mdp, const Eigen::VectorXd& reward, const SoftViOptions& options) {
  SoftBellmanSolver solver(mdp, options);
  return solver.solve(reward);
}

}  // namespace hbirl
