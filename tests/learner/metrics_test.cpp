#include "learner/metrics.hpp"

#include <gtest/gtest.h>

#include "learner/maxcausalent.hpp"
#include "learner/soft_value_iteration.hpp"
#include "random_mdp.hpp"

namespace hbirl {
namespace {

// Brute force: enumerate every (s, a) sequence of each length, weigh it by its
// probability under the policy, and sum the features.
void enumerate(const Mdp& mdp, const Eigen::VectorXd& policy, int s, int steps_left, double p, Eigen::VectorXd& total) {
  if (steps_left == 0 || p == 0.0) return;
  for (int a = 0; a < mdp.num_actions; ++a) {
    const double pa = p * policy[mdp.pair(s, a)];
    if (pa == 0.0) continue;
    total += pa * mdp.features.row(mdp.pair(s, a)).transpose();
    for (int s2 = 0; s2 < mdp.num_states; ++s2) {
      const double pt = mdp.transitions.coeff(mdp.pair(s, a), s2);
      if (pt > 0.0 && !mdp.is_terminal(s2)) enumerate(mdp, policy, s2, steps_left - 1, pa * pt, total);
    }
  }
}

TEST(ExpectedFeatureCounts, MatchBruteForceEnumeration) {
  Rng rng(21);
  testing::RandomMdpOptions o;
  o.states = 4;
  o.actions = 2;
  o.terminal = 1;
  o.impossible = true;
  const Mdp mdp = testing::random_mdp(o, rng);
  const SoftSolution sol = soft_value_iteration(mdp, mdp.reward(testing::random_vector(o.features, rng)));
  const std::vector<int> lengths = {1, 3, 5, 5};
  Eigen::VectorXd brute = Eigen::VectorXd::Zero(o.features);
  for (int length : lengths) {
    for (int s = 0; s < mdp.num_states; ++s) enumerate(mdp, sol.policy, s, length, mdp.start[s], brute);
  }
  brute /= static_cast<double>(lengths.size());
  EXPECT_LT((expected_feature_counts(mdp, sol.policy, lengths) - brute).lpNorm<Eigen::Infinity>(), 1e-12);
}

TEST(FeatureCountError, ZeroWhenTheDataAreTheExpectation) {
  Rng rng(2);
  const Mdp mdp = testing::random_mdp({}, rng);
  const SoftSolution sol = soft_value_iteration(mdp, mdp.reward(testing::random_vector(4, rng)));
  // Counts equal to the expected visits of 3 rollouts of length 4.
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(mdp.num_pairs());
  Eigen::VectorXd d = mdp.start;
  for (int t = 0; t < 4; ++t) {
    Eigen::VectorXd pairs(mdp.num_pairs());
    for (int s = 0; s < mdp.num_states; ++s) {
      pairs.segment(s * mdp.num_actions, mdp.num_actions) =
          d[s] * sol.policy.segment(s * mdp.num_actions, mdp.num_actions);
    }
    counts += 3.0 * pairs;
    d = mdp.transitions.transpose() * pairs;
  }
  EXPECT_LT(feature_count_error(mdp, counts, {4, 4, 4}, sol.policy), 1e-12);
  EXPECT_GT(feature_count_error(mdp, 2.0 * counts, {4, 4, 4}, sol.policy), 0.1);
}

}  // namespace
}  // namespace hbirl

namespace hbirl {
namespace {

// policy_metrics computes one optimal policy per reward for both metrics: the same bits as
// the ILE and the policy agreement computed on their own, on random MDPs (terminal states,
// impossible actions, discounts 0 to 0.99); and the ILE is 0 for the true reward itself.
TEST(PolicyMetrics, SameAsTheIleAndTheAgreementOnTheirOwn) {
  Rng rng(31);
  for (int trial = 0; trial < 30; ++trial) {
    const Mdp mdp = testing::random_mdp(testing::varied_options(trial), rng);
    const Eigen::VectorXd truth = Eigen::VectorXd::Random(mdp.num_features());
    const Eigen::VectorXd learned = Eigen::VectorXd::Random(mdp.num_features());
    const PolicyMetrics both = policy_metrics(mdp, truth, learned);
    const InverseLearningError ile = inverse_learning_error(mdp, truth, learned);
    EXPECT_EQ(both.ile.ile, ile.ile) << trial;
    EXPECT_EQ(both.ile.optimal_value_l1, ile.optimal_value_l1) << trial;
    EXPECT_EQ(both.agreement, policy_agreement(mdp, truth, learned)) << trial;
    EXPECT_GE(both.ile.ile, 0.0) << trial;
    const PolicyMetrics self = policy_metrics(mdp, truth, truth);
    EXPECT_EQ(self.ile.ile, 0.0) << trial;
    EXPECT_EQ(self.agreement, 1.0) << trial;
  }
}

}  // namespace
}  // namespace hbirl
