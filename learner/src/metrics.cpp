#include "learner/metrics.hpp"

#include <algorithm>
#include <cmath>

#include "learner/maxcausalent.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl {

namespace {

// ILE from the two optimal policies: the expert's value is its policy's exact evaluation,
// which value_iteration leaves in .value; the learner's policy is evaluated under the
// true reward, from the expert's values (the same policy: the same values, ILE 0).
InverseLearningError ile_of(const Mdp& mdp, const Eigen::VectorXd& true_reward, const OptimalPolicy& expert,
                            const OptimalPolicy& learner) {
  const Eigen::VectorXd v_learner = learner.actions == expert.actions
                                        ? expert.value
                                        : policy_evaluation(mdp, true_reward, learner.actions, &expert.value);
  InverseLearningError result;
  result.ile = (expert.value - v_learner).lpNorm<1>();
  result.optimal_value_l1 = expert.value.lpNorm<1>();
  return result;
}

double agreement_of(const Mdp& mdp, const OptimalPolicy& expert, const OptimalPolicy& learner) {
  const double tie = 1e-9 * std::max(1.0, expert.value.lpNorm<Eigen::Infinity>());
  int states = 0;
  int agree = 0;
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) continue;
    ++states;
    const double q_learned = expert.q[mdp.pair(s, learner.actions[static_cast<size_t>(s)])];
    if (q_learned >= expert.value[s] - tie) ++agree;
  }
  return states == 0 ? 1.0 : static_cast<double>(agree) / states;
}

}  // namespace

InverseLearningError inverse_learning_error(const Mdp& mdp, const Eigen::VectorXd& true_reward,
                                            const OptimalPolicy& expert, const OptimalPolicy& learner) {
  return ile_of(mdp, true_reward, expert, learner);
}

InverseLearningError inverse_learning_error(const Mdp& mdp, const Eigen::VectorXd& true_theta,
                                            const Eigen::VectorXd& learned_theta) {
  const Eigen::VectorXd true_reward = mdp.reward(true_theta);
  return ile_of(mdp, true_reward, value_iteration(mdp, true_reward), value_iteration(mdp, mdp.reward(learned_theta)));
}

double policy_agreement(const Mdp& mdp, const Eigen::VectorXd& true_theta, const Eigen::VectorXd& learned_theta) {
  return agreement_of(mdp, value_iteration(mdp, mdp.reward(true_theta)),
                      value_iteration(mdp, mdp.reward(learned_theta)));
}

PolicyMetrics policy_metrics(const Mdp& mdp, const Eigen::VectorXd& true_theta, const Eigen::VectorXd& learned_theta) {
  return policy_metrics(mdp, true_theta, value_iteration(mdp, mdp.reward(learned_theta)));
}

PolicyMetrics policy_metrics(const Mdp& mdp, const Eigen::VectorXd& true_theta, const OptimalPolicy& learner) {
  const Eigen::VectorXd true_reward = mdp.reward(true_theta);
  const OptimalPolicy expert = value_iteration(mdp, true_reward);
  return {ile_of(mdp, true_reward, expert, learner), agreement_of(mdp, expert, learner)};
}

Eigen::VectorXd expected_feature_counts(const Mdp& mdp, const Eigen::VectorXd& policy,
                                        const std::vector<int>& lengths) {
  const int horizon = lengths.empty() ? 0 : *std::max_element(lengths.begin(), lengths.end());
  const int A = mdp.num_actions;
  Eigen::VectorXd total = Eigen::VectorXd::Zero(mdp.num_features());
  if (lengths.empty()) return total;
  Eigen::VectorXd d = mdp.start;  // state distribution at step t (mass not yet terminated)
  Eigen::VectorXd pairs(mdp.num_pairs());
  for (int t = 0; t < horizon; ++t) {
    // Share of trajectories that are still running at step t.
    const auto running = std::count_if(lengths.begin(), lengths.end(), [t](int l) { return l > t; });
    const double share = static_cast<double>(running) / static_cast<double>(lengths.size());
    for (int s = 0; s < mdp.num_states; ++s) {
      pairs.segment(static_cast<Eigen::Index>(s) * A, A) = d[s] * policy.segment(static_cast<Eigen::Index>(s) * A, A);
    }
    total.noalias() += share * (mdp.features.transpose() * pairs);
    d.noalias() = mdp.transitions.transpose() * pairs;
    for (int s = 0; s < mdp.num_states; ++s) {
      if (mdp.is_terminal(s)) d[s] = 0.0;
    }
  }
  return total;
}

double feature_count_error(const Mdp& mdp, const Eigen::VectorXd& counts, const std::vector<int>& lengths,
                           const Eigen::VectorXd& policy) {
  if (lengths.empty()) return 0.0;
  const Eigen::VectorXd empirical = empirical_feature_counts(mdp, counts) / static_cast<double>(lengths.size());
  return (empirical - expected_feature_counts(mdp, policy, lengths)).lpNorm<1>();
}

}  // namespace hbirl
