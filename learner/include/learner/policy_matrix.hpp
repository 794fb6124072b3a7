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
#include "learner/policy_operator.hpp"

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
  // BiCGSTAB's iterations in the last solve (each two products with the matrix): what
  // docs/BENCHMARKS.md counts bytes by.
  int last_iterations() const { return last_iterations_; }
  long long bytes_per_product(bool transposed) const {
    return (transposed ? transposed_operator_ : operator_).bytes_per_product();
  }

 private:
  // BiCGSTAB with Eigen's diagonal preconditioner, its products by PolicyOperator (the
  // same bits as Eigen's sparse product, faster on grids).
  using Solver = Eigen::BiCGSTAB<PolicyOperator, InverseDiagonalPreconditioner>;
  bool run(Solver& solver, PolicyOperator& op, bool& stale, const Eigen::VectorXd& b, Eigen::VectorXd& x,
           double tolerance);

  const Mdp& mdp_;
  SparseRowMatrix matrix_;  // S x S
  PolicyOperator operator_;
  PolicyOperator transposed_operator_;
  bool operator_stale_ = true;  // the operators' copies of matrix_'s values
  bool transposed_stale_ = true;
  std::vector<int> entry_slot_;     // transitions nnz -> index into matrix_ values
  std::vector<int> diagonal_slot_;  // state -> index of its diagonal entry
  Solver solver_;
  Solver transposed_solver_;
  int last_iterations_ = 0;
};

}  // namespace hbirl
