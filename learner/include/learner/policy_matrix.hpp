#pragma once
// The matrix (I - gamma * P_pi) of a stochastic policy pi over (s, a) pairs, where
// P_pi(s, s') = sum_a pi(a|s) T(s'|s,a). Rows of terminal states are identity rows, so
// solving (I - gamma P_pi) x = b with b(terminal) = 0 gives x(terminal) = 0: the value of
// a state that ends the trajectory.
//
// Used for exact policy evaluation, for the Newton step of soft value iteration (soft
// policy evaluation) and for the adjoint solve of the MaxCausalEnt gradient. The
// sparsity pattern is fixed per MDP (the union of the successors of each state's
// actions, plus the diagonal), so changing the policy only rewrites values.
#include <Eigen/IterativeLinearSolvers>

#include "learner/mdp.hpp"

namespace hbirl {

class PolicyMatrix {
 public:
  static constexpr double kWorkingTolerance = 1e-14;

  explicit PolicyMatrix(const Mdp& mdp);

  // policy: one probability per (s, a) pair; rows of terminal states are ignored.
  void set_policy(const Eigen::VectorXd& policy);
  // Deterministic policy: one action per state (ignored for terminal states).
  void set_policy(const std::vector<int>& actions);

  // Solve (I - gamma P_pi) x = b. x holds the initial guess on entry. Returns false
  // if the iterative solver did not reach the tolerance (x then holds its best try).
  // tolerance: the relative residual ||b - M x|| / ||b|| to reach (inexact Newton steps
  // ask for less than working precision).
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance = kWorkingTolerance);
  // Solve (I - gamma P_pi)^T x = b, same conventions.
  bool solve_transposed(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  const SparseRowMatrix& matrix() const { return matrix_; }

 private:
  using Solver = Eigen::BiCGSTAB<SparseRowMatrix, Eigen::DiagonalPreconditioner<double>>;
  bool run(Solver& solver, const SparseRowMatrix& a, const Eigen::VectorXd& b, Eigen::VectorXd& x, double tolerance);

  const Mdp& mdp_;
  SparseRowMatrix matrix_;      // S x S
  SparseRowMatrix transposed_;  // its pattern fixed at construction, its values copied on demand
  bool transposed_stale_ = true;
  std::vector<int> transposed_slot_;  // transposed_ entry -> index into matrix_ values
  std::vector<int> entry_slot_;       // transitions nnz -> index into matrix_ values
  std::vector<int> diagonal_slot_;    // state -> index of its diagonal entry
  Solver solver_;
  Solver transposed_solver_;
};

}  // namespace hbirl
