#pragma once
// The MaxCausalEnt M-step objective (paper §II-A) and its exact gradient.
//
// Choice (documented in docs/MODEL.md): the objective is the causal log-likelihood of
// the demonstrated state-action visits under the stationary soft policy pi_theta of
// soft_value_iteration.hpp,
//     L(theta) = sum_{s,a} N(s,a) log pi_theta(a|s),
// where N(s,a) counts the visits to (s, a) in the finite trajectories (or, inside
// HiddenDataEM, their expectation under the E-step posterior; then this is exactly the
// expected complete-data log-likelihood, so EM never decreases the data likelihood).
// Every visited step counts once, undiscounted; trajectory lengths and start states
// enter only through which pairs were visited.
//
// Gradient. With psi(s,a) = dQ(s,a)/dtheta the discounted successor features of pi,
//     dL/dtheta = sum_{s,a} (N(s,a) - n(s) pi(a|s)) psi(s,a),   n(s) = sum_a N(s,a),
// which we evaluate with one adjoint solve instead of K forward ones:
//     w   = N - n * pi                          (per pair)
//     rho = T^T w                               (per next state)
//     x   = (I - gamma P_pi^T)^{-1} rho
//     dL/dtheta = phi_hat - E_theta[phi],
//         phi_hat     = Phi^T N                        (empirical feature counts)
//         E_theta[phi] = Phi^T ((n - gamma x) * pi)     (the policy's expected features
//                        at the demonstrated state visits, corrected by the discounted
//                        effect of the actions it would have chosen instead).
// So the gradient is the MaxCausalEnt "feature counts minus expected feature counts",
// with the expectation taken at the data's own start states and horizons.
#include <optional>

#include "learner/mdp.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl {

class CausalLikelihood {
 public:
  // counts: N(s,a) per pair (non-negative; none on impossible pairs or terminal states).
  // l2: penalty weight, see evaluate(). Throws InputError for invalid counts.
  CausalLikelihood(const Mdp& mdp, Eigen::VectorXd counts, double l2 = 0.0, SoftViOptions soft_vi = {});

  // J(theta) = L(theta) / M - (l2 / 2) ||theta||^2, with M = sum N the number of
  // visited steps (so tolerances and l2 do not depend on the data size).
  // Fills *gradient with dJ/dtheta when it is not null.
  double evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient);

  // Of the last evaluate(): the unnormalised, unpenalised L(theta) and the soft solution.
  double log_likelihood() const { return log_likelihood_; }
  const SoftSolution& solution() const { return solver_.solution(); }
  double total_count() const { return total_; }
  // Solve the next evaluation's soft Bellman equation from V = 0 (benchmarks use this to
  // time a cold evaluation; normally each solve starts from the previous one).
  void cold_start() { solver_.forget_warm_start(); }
  // Solve the next evaluation's soft Bellman equation from this solution (one already
  // solved at or near the next theta, e.g. by the E-step).
  void warm_start(const SoftSolution& solution) { solver_.warm_start(solution.value); }
  double l2() const { return l2_; }

 private:
  const Mdp& mdp_;
  Eigen::VectorXd counts_;
  Eigen::VectorXd state_counts_;
  std::vector<int> visited_;  // pairs with N > 0
  double total_ = 0.0;
  double l2_ = 0.0;
  double log_likelihood_ = 0.0;
  SoftBellmanSolver solver_;
};

// phi_hat = Phi^T N: the feature counts of a set of visits.
Eigen::VectorXd empirical_feature_counts(const Mdp& mdp, const Eigen::VectorXd& counts);

}  // namespace hbirl
