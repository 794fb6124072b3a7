#include "learner/policy_matrix.hpp"

#include <algorithm>
#include <stdexcept>

namespace hbirl {

namespace {
int slot_of(const SparseRowMatrix& m, int row, int col) {
  const int* begin = m.innerIndexPtr() + m.outerIndexPtr()[row];
  const int* end = m.innerIndexPtr() + m.outerIndexPtr()[row + 1];
  const int* it = std::lower_bound(begin, end, col);
  if (it == end || *it != col) throw std::logic_error("PolicyMatrix: pattern is missing an entry");
  return static_cast<int>(it - m.innerIndexPtr());
}
}  // namespace

PolicyMatrix::PolicyMatrix(const Mdp& mdp) : mdp_(mdp) {
  const int S = mdp.num_states;
  const int A = mdp.num_actions;
  const SparseRowMatrix& t = mdp.transitions;
  std::vector<Eigen::Triplet<double, int>> pattern;
  pattern.reserve(static_cast<size_t>(t.nonZeros() + S));
  for (int s = 0; s < S; ++s) {
    pattern.emplace_back(s, s, 0.0);
    if (mdp.is_terminal(s)) continue;
    for (int a = 0; a < A; ++a) {
      const int r = mdp.pair(s, a);
      for (int j = t.outerIndexPtr()[r]; j < t.outerIndexPtr()[r + 1]; ++j) {
        pattern.emplace_back(s, t.innerIndexPtr()[j], 0.0);
      }
    }
  }
  matrix_.resize(S, S);
  matrix_.setFromTriplets(pattern.begin(), pattern.end());
  matrix_.makeCompressed();

  operator_ = PolicyOperator(matrix_, false);
  transposed_operator_ = PolicyOperator(matrix_, true);

  entry_slot_.assign(static_cast<size_t>(t.nonZeros()), -1);
  diagonal_slot_.resize(static_cast<size_t>(S));
  for (int s = 0; s < S; ++s) {
    diagonal_slot_[static_cast<size_t>(s)] = slot_of(matrix_, s, s);
    if (mdp.is_terminal(s)) continue;
    for (int a = 0; a < A; ++a) {
      const int r = mdp.pair(s, a);
      for (int j = t.outerIndexPtr()[r]; j < t.outerIndexPtr()[r + 1]; ++j) {
        entry_slot_[static_cast<size_t>(j)] = slot_of(matrix_, s, t.innerIndexPtr()[j]);
      }
    }
  }
}

void PolicyMatrix::set_policy(const Eigen::VectorXd& policy) {
  const int S = mdp_.num_states;
  const int A = mdp_.num_actions;
  const double gamma = mdp_.discount;
  const SparseRowMatrix& t = mdp_.transitions;
  double* value = matrix_.valuePtr();
  std::fill(value, value + matrix_.nonZeros(), 0.0);
  for (int s = 0; s < S; ++s) {
    value[diagonal_slot_[static_cast<size_t>(s)]] = 1.0;
    if (mdp_.is_terminal(s)) continue;
    for (int a = 0; a < A; ++a) {
      const int r = mdp_.pair(s, a);
      const double weight = gamma * policy[r];
      if (weight == 0.0) continue;
      for (int j = t.outerIndexPtr()[r]; j < t.outerIndexPtr()[r + 1]; ++j) {
        value[entry_slot_[static_cast<size_t>(j)]] -= weight * t.valuePtr()[j];
      }
    }
  }
  operator_stale_ = true;
  transposed_stale_ = true;
}

void PolicyMatrix::set_policy(const std::vector<int>& actions) {
  Eigen::VectorXd policy = Eigen::VectorXd::Zero(mdp_.num_pairs());
  for (int s = 0; s < mdp_.num_states; ++s) {
    if (!mdp_.is_terminal(s)) policy[mdp_.pair(s, actions[static_cast<size_t>(s)])] = 1.0;
  }
  set_policy(policy);
}

bool PolicyMatrix::run(Solver& solver, PolicyOperator& op, bool& stale, const Eigen::VectorXd& b, Eigen::VectorXd& x,
                       double tolerance) {
  if (stale) {
    op.update_values(matrix_);
    stale = false;
  }
  solver.setTolerance(tolerance);
  solver.compute(op);
  Eigen::VectorXd guess = x;
  x = solver.solveWithGuess(b, guess);
  last_iterations_ = static_cast<int>(solver.iterations());
  if (solver.info() == Eigen::Success) return true;
  // BiCGSTAB may stop a hair above a very tight tolerance; accept what a direct residual
  // check says is accurate to working precision.
  const double scale = std::max(1.0, b.lpNorm<Eigen::Infinity>());
  if (!x.allFinite()) return false;
  const Eigen::VectorXd residual = b - op * x;
  return residual.lpNorm<Eigen::Infinity>() <= std::max(1e-11, tolerance) * scale;
}

bool PolicyMatrix::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance) {
  return run(solver_, operator_, operator_stale_, b, x, tolerance);
}

bool PolicyMatrix::solve_transposed(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  return run(transposed_solver_, transposed_operator_, transposed_stale_, b, x, kWorkingTolerance);
}

}  // namespace hbirl
