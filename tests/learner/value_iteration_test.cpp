#include "learner/value_iteration.hpp"

#include <gtest/gtest.h>

#include "learner/metrics.hpp"
#include "random_mdp.hpp"
#include "sim_driver/gridworld.hpp"

namespace hbirl {
namespace {

// Two states; action 1 in state 0 moves to state 1, which pays 1 per step for staying.
// V*(1) = 1 / (1 - gamma); V*(0) = gamma V*(1) (move, then collect).
TEST(ValueIteration, TwoStateHandComputed) {
  const double gamma = 0.8;
  Mdp mdp = make_mdp(2, 2, 1, {{0, 0, 0, 1.0}, {0, 1, 1, 1.0}, {1, 0, 1, 1.0}, {1, 1, 0, 1.0}},
                     {{1, 0, 0, 1.0}}, Eigen::Vector2d(1, 0), {}, gamma);
  mdp.validate();
  const OptimalPolicy opt = value_iteration(mdp, mdp.reward(Eigen::VectorXd::Ones(1)));
  EXPECT_NEAR(opt.value[1], 5.0, 1e-10);
  EXPECT_NEAR(opt.value[0], 4.0, 1e-10);
  EXPECT_EQ(opt.actions, (std::vector<int>{1, 0}));
}

TEST(PolicyEvaluation, MatchesTheBellmanEquation) {
  Rng rng(4);
  testing::RandomMdpOptions o;
  o.terminal = 1;
  o.impossible = true;
  const Mdp mdp = testing::random_mdp(o, rng);
  const Eigen::VectorXd reward = mdp.reward(testing::random_vector(o.features, rng));
  // A random stochastic policy over the possible actions.
  Eigen::VectorXd policy = Eigen::VectorXd::Zero(mdp.num_pairs());
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) continue;
    double total = 0.0;
    for (int a = 0; a < mdp.num_actions; ++a) {
      if (mdp.available(s, a)) total += (policy[mdp.pair(s, a)] = 0.1 + rng.uniform());
    }
    policy.segment(s * mdp.num_actions, mdp.num_actions) /= total;
  }
  const Eigen::VectorXd v = policy_evaluation(mdp, reward, policy);
  for (int s = 0; s < mdp.num_states; ++s) {
    double expected = 0.0;
    for (int a = 0; a < mdp.num_actions; ++a) {
      const int r = mdp.pair(s, a);
      if (policy[r] == 0.0) continue;
      double next = 0.0;
      for (int s2 = 0; s2 < mdp.num_states; ++s2) next += mdp.transitions.coeff(r, s2) * v[s2];
      expected += policy[r] * (reward[r] + mdp.discount * next);
    }
    EXPECT_NEAR(v[s], expected, 1e-11);
  }
}

// The optimal policy found is at least as good as every deterministic policy
// (enumerated exhaustively on a small random MDP).
TEST(ValueIteration, BeatsEveryDeterministicPolicy) {
  Rng rng(8);
  testing::RandomMdpOptions o;
  o.states = 5;
  o.actions = 3;
  const Mdp mdp = testing::random_mdp(o, rng);
  const Eigen::VectorXd reward = mdp.reward(testing::random_vector(o.features, rng));
  const OptimalPolicy opt = value_iteration(mdp, reward);
  std::vector<int> actions(5, 0);
  for (int code = 0; code < 243; ++code) {
    int c = code;
    for (int s = 0; s < 5; ++s, c /= 3) actions[static_cast<size_t>(s)] = c % 3;
    const Eigen::VectorXd v = policy_evaluation(mdp, reward, actions);
    EXPECT_TRUE((opt.value.array() >= v.array() - 1e-9).all()) << code;
  }
}

TEST(InverseLearningError, ZeroForTheTrueRewardAndPositiveForTheWrongOne) {
  const Mdp mdp = make_gridworld();
  const Eigen::Vector4d truth(1, 0, 0, 0);
  const InverseLearningError same = inverse_learning_error(mdp, truth, truth);
  EXPECT_EQ(same.ile, 0.0);
  EXPECT_GT(same.optimal_value_l1, 0.0);
  // Scaling the reward does not change the optimal policy.
  EXPECT_LT(inverse_learning_error(mdp, truth, 3.0 * truth).ile, 1e-9);
  const InverseLearningError wrong = inverse_learning_error(mdp, truth, Eigen::Vector4d(0, 0, 0, 1));
  EXPECT_GT(wrong.relative(), 0.1);
  EXPECT_EQ(policy_agreement(mdp, truth, truth), 1.0);
  EXPECT_LT(policy_agreement(mdp, truth, Eigen::Vector4d(0, 0, 0, 1)), 0.5);
}

}  // namespace
}  // namespace hbirl
