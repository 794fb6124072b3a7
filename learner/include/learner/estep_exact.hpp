#pragma once
// The exact E-step engine (SPEC §2, engine 1). The source label Z of each observation is
// summed out,
//   p(w | s,a) = eta(0) O_{s,a}(w) + sum_e eta(e) O_e(w),
// so a trajectory is a chain over (s, a) pairs with emission prod_n p(w_n | s_t, a_t) at
// step t, solved exactly by forward-backward. Everything is in log space: emissions are
// sums of logs (thousands of observations per step cannot underflow), and the messages
// combine with log-sum-exp over the sparse transitions, so deterministic transitions,
// occluded steps (no observations: emission 1) and long trajectories are all exact.
// The posteriors of Z and the expected counts alpha_dot follow in closed form from the
// (s, a) marginals:
//   Pr(Z = 0 | data) = sum_r gamma_t(r) eta(0) O_r(w) / p(w | r)
//   Pr(Z = e | data) = sum_r gamma_t(r) eta(e) O_e(w) / p(w | r).
#include "learner/mdp.hpp"
#include "learner/observation_model.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl {

struct TrajectoryPosterior {
  double log_likelihood = 0.0;  // log Pr(observations | theta, O); -inf if impossible
  RowMatrix marginals;          // T x (S*A): Pr(s_t = s, a_t = a | data)
  RowMatrix sources;            // one row per observation: Pr(Z = z | data), subject first
};

// What the E-step sums over trajectories.
struct EStepStatistics {
  Eigen::VectorXd counts;       // expected visits per (s, a) pair
  AlphaCounts alpha_dot;        // expected source-labelled counts
  double log_likelihood = 0.0;
  int impossible = 0;           // trajectories with probability 0 under the model (skipped)

  static EStepStatistics zero(int pairs, int confounders, int symbols);
  EStepStatistics& operator+=(const EStepStatistics& other);
};

// Forward-backward workspace bound to one MDP (which must outlive it).
class ExactEngine {
 public:
  explicit ExactEngine(const Mdp& mdp);

  TrajectoryPosterior posterior(const SoftSolution& policy, const ObservationModel& model,
                                const ObservedTrajectory& trajectory);
  // log Pr(observations | theta, O) by the forward pass alone.
  double log_likelihood(const SoftSolution& policy, const ObservationModel& model,
                        const ObservedTrajectory& trajectory) {
    return forward_backward(policy, model, trajectory, false);
  }
  // Adds the trajectory's expected visits, alpha_dot and log-likelihood to `out`.
  void accumulate(const SoftSolution& policy, const ObservationModel& model,
                  const ObservedTrajectory& trajectory, EStepStatistics& out);

 private:
  // Fills log_emission_, log_alpha_ and (with_backward) log_beta_; returns the
  // log-likelihood.
  double forward_backward(const SoftSolution& policy, const ObservationModel& model,
                          const ObservedTrajectory& trajectory, bool with_backward = true);
  // gamma_t = exp(log_alpha_t + log_beta_t - ll) into marginal_.
  void marginal(int t, double log_likelihood);
  // Per observation: p(w | r) for every pair and the part sum_e eta(e) O_e(w).
  double mixture(const ObservationModel& model, const ObservedTrajectory& trajectory, int n);

  const Mdp& mdp_;
  SparseRowMatrix incoming_;         // S x (S*A), T transposed
  SparseRowMatrix log_transitions_;  // (S*A) x S, log T
  SparseRowMatrix log_incoming_;     // S x (S*A), log T transposed
  Eigen::VectorXd log_start_;
  RowMatrix log_emission_;           // T x (S*A)
  RowMatrix log_alpha_;
  RowMatrix log_beta_;
  Eigen::VectorXd marginal_;
  Eigen::ArrayXd p_;                 // p(w | r) of one observation
  Eigen::VectorXd scratch_;
};

}  // namespace hbirl
