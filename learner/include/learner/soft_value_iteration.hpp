#pragma once
// Soft (maximum causal entropy) value iteration and the stationary soft policy of
// the paper's appendix (docs/MODEL.md "The expert: the stationary soft policy"):
//   Q(s,a) = R(s,a) + gamma * sum_s' T(s'|s,a) V(s')
//   V(s)   = logsumexp_a Q(s,a)
//   pi(a|s) = exp(Q(s,a) - V(s))
// Everything is kept in log space: impossible actions have Q = -inf (exp(-inf) = 0 is
// exactly the probability we want, and logsumexp subtracts the max first, so large
// rewards never overflow). Terminal states have V = 0 and no policy.
#include <memory>

#include "learner/mdp.hpp"
#include "learner/policy_matrix.hpp"

namespace hbirl {

enum class SoftViMethod {
  // Soft policy iteration: each step evaluates the current soft policy exactly, which is
  // Newton's method on the soft Bellman equation (quadratic convergence). Default.
  kNewton,
  // Plain repeated Bellman backups (contraction by gamma per step). Reference method.
  kFixedPoint,
};

struct SoftViOptions {
  SoftViMethod method = SoftViMethod::kNewton;
  // Converged when max_s |V_new(s) - V(s)| <= tolerance * max(1, max_s |V(s)|).
  double tolerance = 1e-13;
  int max_iterations = 100000;  // Bellman backups
};

struct SoftSolution {
  Eigen::VectorXd value;       // V(s); 0 at terminal states
  Eigen::VectorXd q;           // Q(s,a) per pair; -inf for impossible actions, terminal states
  Eigen::VectorXd log_policy;  // log pi(a|s) per pair; -inf where pi = 0
  Eigen::VectorXd policy;      // pi(a|s) per pair; 0 on terminal states
  int iterations = 0;          // Bellman backups made
  int newton_steps = 0;        // soft policy evaluations made
  double residual = 0.0;       // max |logsumexp Q(V) - V| at exit
  bool converged = false;
};

// A soft Bellman solver bound to one MDP (which must outlive it). Reuses its workspace
// and warm-starts from its previous solution, which makes repeated solves for nearby
// rewards (an optimiser's line search) cheap. Deterministic: the result depends only
// on the sequence of rewards (and warm_start values) it was given.
class SoftBellmanSolver {
 public:
  explicit SoftBellmanSolver(const Mdp& mdp, SoftViOptions options = {});

  const SoftSolution& solve(const Eigen::VectorXd& reward);
  const SoftSolution& solution() const { return solution_; }
  void forget_warm_start() {
    has_solution_ = false;
    has_adjoint_ = false;
  }
  // Start the next solve from these values: another solver's solution at the same or a
  // nearby reward (HiddenDataEM's M-step starts where its E-step solved).
  void warm_start(const Eigen::VectorXd& value);

  // x = (I - gamma P_pi^T)^{-1} rhs for the policy of the last solve; entries for
  // terminal states are meaningless (they multiply zero policy rows). Starts from the
  // last adjoint solution (an optimiser's consecutive points are near each other).
  Eigen::VectorXd solve_adjoint(const Eigen::VectorXd& rhs);

 private:
  // One Bellman backup: q = R + gamma T v (-inf where impossible), v_new = logsumexp q.
  void backup(const Eigen::VectorXd& reward, const Eigen::VectorXd& v);
  void policy_from_q();

  const Mdp& mdp_;
  SoftViOptions options_;
  PolicyMatrix policy_matrix_;
  bool has_solution_ = false;
  bool has_adjoint_ = false;
  Eigen::VectorXd adjoint_;  // the last solve_adjoint's solution
  bool policy_matrix_current_ = false;
  SoftSolution solution_;
  Eigen::VectorXd v_new_;
  std::vector<int> impossible_pairs_;
};

// One-shot convenience: solve from V = 0.
SoftSolution soft_value_iteration(const Mdp& mdp, const Eigen::VectorXd& reward, const SoftViOptions& options = {});

// The stationary soft policy pi(a|s) = exp(Q(s,a) - V(s)) of a solved soft Bellman
// equation, one probability per (s, a) pair.
inline const Eigen::VectorXd& soft_policy(const SoftSolution& solution) { return solution.policy; }

}  // namespace hbirl
