#pragma once
// How good is a learned reward? (paper §II; docs/MODEL.md "Metrics".)
#include <vector>

#include "learner/mdp.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl {

struct InverseLearningError {
  double ile = 0.0;               // ||V^{pi_E} - V^{pi_L}||_1
  double optimal_value_l1 = 0.0;  // ||V^{pi_E}||_1, the scale to judge ile against
  double relative() const { return optimal_value_l1 > 0.0 ? ile / optimal_value_l1 : ile; }
};

// "Near optimal": the learned policy loses at most this share of the optimal value
// (relative ILE <= 0.05) -- what hbirl's confidence is the probability of, and what the
// experiments count as right (docs/MODEL.md "Metrics").
constexpr double kNearOptimalShare = 0.05;

// ILE = ||V^{pi_E} - V^{pi_L}||_1 where pi_E is optimal for the true reward, pi_L is
// optimal for the learned reward, and both are evaluated exactly (policy evaluation, not
// a one-step estimate) under the TRUE reward.
InverseLearningError inverse_learning_error(const Mdp& mdp, const Eigen::VectorXd& true_theta,
                                            const Eigen::VectorXd& learned_theta);

// The same from both rewards' optimal policies already planned (value_iteration): for many
// true rewards against one learned policy (reward_posterior.hpp's confidence) without
// planning the learned reward again.
InverseLearningError inverse_learning_error(const Mdp& mdp, const Eigen::VectorXd& true_reward,
                                            const OptimalPolicy& expert, const OptimalPolicy& learner);

// Share of non-terminal states where the learned reward's optimal action is also optimal
// under the true reward (ties within 1e-9 of the value scale count as optimal).
double policy_agreement(const Mdp& mdp, const Eigen::VectorXd& true_theta, const Eigen::VectorXd& learned_theta);

// Both, from one optimal policy per reward (what the two above would compute twice each).
struct PolicyMetrics {
  InverseLearningError ile;
  double agreement = 0.0;
};
PolicyMetrics policy_metrics(const Mdp& mdp, const Eigen::VectorXd& true_theta, const Eigen::VectorXd& learned_theta);
// The same with the learned reward's optimal policy already planned (value_iteration): a
// caller that also shows that policy plans it once (app/output.hpp).
PolicyMetrics policy_metrics(const Mdp& mdp, const Eigen::VectorXd& true_theta, const OptimalPolicy& learner);

// E[phi] of a policy (one probability per pair), averaged over rollouts from the start
// distribution, one rollout per entry of `lengths` (trajectories stop early when they
// enter a terminal state).
Eigen::VectorXd expected_feature_counts(const Mdp& mdp, const Eigen::VectorXd& policy, const std::vector<int>& lengths);

// ||phi_hat - E_pi[phi]||_1 per trajectory: phi_hat from the visit counts of the data,
// E_pi[phi] from rollouts with the data's lengths.
double feature_count_error(const Mdp& mdp, const Eigen::VectorXd& counts, const std::vector<int>& lengths,
                           const Eigen::VectorXd& policy);

}  // namespace hbirl
