#include "learner/value_iteration.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "learner/metrics.hpp"
#include "random_mdp.hpp"
#include "sim_driver/gridworld/gridworld.hpp"

namespace hbirl {
namespace {

// Two states; action 1 in state 0 moves to state 1, which pays 1 per step for staying.
// V*(1) = 1 / (1 - gamma); V*(0) = gamma V*(1) (move, then collect).
TEST(ValueIteration, TwoStateHandComputed) {
  const double gamma = 0.8;
  Mdp mdp = make_mdp(2, 2, 1, {{0, 0, 0, 1.0}, {0, 1, 1, 1.0}, {1, 0, 1, 1.0}, {1, 1, 0, 1.0}}, {{1, 0, 0, 1.0}},
                     Eigen::Vector2d(1, 0), {}, gamma);
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

// Against plain value iteration written out here (Jacobi sweeps of the Bellman equation
// to 1e-13, then the greedy policy): on random MDPs with self-loops, terminal states,
// impossible actions, deterministic moves and discounts 0, 0.9 and 0.99, the optimal
// values agree and each chosen action attains the maximum.
TEST(ValueIteration, AgreesWithPlainValueIteration) {
  Rng rng(21);
  for (int trial = 0; trial < 60; ++trial) {
    testing::RandomMdpOptions o = testing::varied_options(trial);
    o.states += 10;
    const Mdp mdp = testing::random_mdp(o, rng);
    const Eigen::VectorXd reward = mdp.reward(testing::random_vector(o.features, rng, 5.0));
    Eigen::VectorXd v = Eigen::VectorXd::Zero(mdp.num_states);
    Eigen::VectorXd q(mdp.num_pairs());
    for (int sweep = 0; sweep < 100000; ++sweep) {
      Eigen::VectorXd next = Eigen::VectorXd::Zero(mdp.num_states);
      for (int s = 0; s < mdp.num_states; ++s) {
        double best = -INFINITY;
        for (int a = 0; a < mdp.num_actions; ++a) {
          const int r = mdp.pair(s, a);
          q[r] = -INFINITY;
          if (mdp.is_terminal(s) || !mdp.available(s, a)) continue;
          double expected = 0.0;
          for (int s2 = 0; s2 < mdp.num_states; ++s2) expected += mdp.transitions.coeff(r, s2) * v[s2];
          q[r] = reward[r] + mdp.discount * expected;
          best = std::max(best, q[r]);
        }
        next[s] = mdp.is_terminal(s) ? 0.0 : best;
      }
      const double change = (next - v).lpNorm<Eigen::Infinity>();
      v = next;
      if (change <= 1e-13 * std::max(1.0, v.lpNorm<Eigen::Infinity>())) break;
    }
    const OptimalPolicy opt = value_iteration(mdp, reward);
    // The sweeps themselves must reach V*: policy iteration would repair a wrong fixed
    // point from any greedy policy, but not in at most one step.
    EXPECT_LE(opt.policy_iterations, 1) << "trial " << trial;
    const double scale = std::max(1.0, v.lpNorm<Eigen::Infinity>());
    EXPECT_LT((opt.value - v).lpNorm<Eigen::Infinity>(), 1e-9 * scale) << "trial " << trial;
    for (int s = 0; s < mdp.num_states; ++s) {
      if (mdp.is_terminal(s)) continue;
      EXPECT_GE(q[mdp.pair(s, opt.actions[static_cast<size_t>(s)])], v[s] - 1e-9 * scale)
          << "trial " << trial << " state " << s;
    }
  }
}

TEST(ValueIteration, NonFiniteRewardIsRefused) {
  Rng rng(4);
  const Mdp mdp = testing::random_mdp({}, rng);
  Eigen::VectorXd reward = Eigen::VectorXd::Zero(mdp.num_pairs());
  reward[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(value_iteration(mdp, reward), std::domain_error);
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
