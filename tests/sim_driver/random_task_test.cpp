#include "sim_driver/file/random_task.hpp"

#include <gtest/gtest.h>

#include <set>

#include "learner/input_error.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl {
namespace {

// Every drawn task stays inside the documented ranges, is a valid MDP whose true reward's
// optimal policy is not trivial, and its data have the shapes the learner needs.
TEST(RandomTask, DrawsStayInTheirRanges) {
  std::set<std::string> layouts;
  std::set<int> confounders;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    const RandomTask t = make_random_task(seed);
    SCOPED_TRACE("seed " + std::to_string(seed));
    layouts.insert(t.layout);
    confounders.insert(t.num_confounders);
    EXPECT_NO_THROW(t.mdp.validate());
    EXPECT_GE(t.mdp.num_states, 9);
    EXPECT_LE(t.mdp.num_states, 100);
    EXPECT_GE(t.mdp.num_actions, 2);
    EXPECT_LE(t.mdp.num_actions, 6);
    EXPECT_GE(t.goals, 1);
    EXPECT_GE(t.goals + t.traps, 1);
    EXPECT_LE(t.goals + t.traps, 3);
    int terminal = 0;
    for (int s = 0; s < t.mdp.num_states; ++s) terminal += t.mdp.is_terminal(s) ? 1 : 0;
    EXPECT_EQ(terminal, t.goals + t.traps);
    EXPECT_GE(t.mdp.num_features(), 2);
    EXPECT_LE(t.mdp.num_features(), 5);
    EXPECT_EQ(t.feature_names[0], "step");
    EXPECT_LT(t.true_weights[0], 0.0);  // a cost
    EXPECT_GT(t.true_weights[1], 0.0);  // the goal
    for (int s = 0; s < t.mdp.num_states; ++s) {
      for (int a = 0; a < t.mdp.num_actions; ++a) {
        if (!t.mdp.is_terminal(s) && t.mdp.available(s, a)) {
          EXPECT_EQ(t.mdp.features(t.mdp.pair(s, a), 0), 1.0);
        }
      }
    }
    const OptimalPolicy optimal = value_iteration(t.mdp, t.mdp.reward(t.true_weights));
    std::set<int> used;
    for (int a : optimal.actions) {
      if (a >= 0) used.insert(a);
    }
    EXPECT_GE(used.size(), 2u);
    EXPECT_GT(t.decisiveness, 0.0);
    EXPECT_LE(t.decisiveness, 1.0);
    EXPECT_GE(t.num_symbols, 4);
    EXPECT_LE(t.num_symbols, 24);
    EXPECT_LE(t.num_confounders, 7);
    EXPECT_LE(t.occlusion, 0.3);
    EXPECT_GE(t.informativeness, 0.3);
    EXPECT_GE(t.demonstrations.size(), 5u);
    EXPECT_LE(t.demonstrations.size(), 40u);
    ASSERT_EQ(t.observed.trajectories.size(), t.demonstrations.size());
    for (size_t i = 0; i < t.demonstrations.size(); ++i) {
      const ObservedTrajectory& o = t.observed.trajectories[i];
      EXPECT_EQ(o.length(), static_cast<int>(t.demonstrations[i].size()));
      EXPECT_EQ(o.eta.cols(), 1 + t.num_confounders);
      EXPECT_EQ(t.observed.true_sources[i].size(), o.symbols.size());
      // Cut off before the length only by entering a terminal state.
      if (static_cast<int>(t.demonstrations[i].size()) < t.length) {
        EXPECT_TRUE(o.ends_in_terminal);
      }
      // The terminal state entered is recorded (the oracles' end), one the last step can reach;
      // what the learner is given does not carry it.
      EXPECT_EQ(t.entered[i] >= 0, o.ends_in_terminal);
      if (t.entered[i] >= 0) {
        EXPECT_TRUE(t.mdp.is_terminal(t.entered[i]));
        const StateAction& last = t.demonstrations[i].back();
        EXPECT_GT(t.mdp.transitions.coeff(t.mdp.pair(last.state, last.action), t.entered[i]), 0.0);
      }
      EXPECT_EQ(o.end_state, -1);
    }
    EXPECT_EQ(t.prior.subject_alpha.rows(), t.mdp.num_pairs());
    EXPECT_EQ(t.prior.confounder_alpha.rows(), t.num_confounders);
    for (Eigen::Index r = 0; r < t.subject_o.rows(); ++r) EXPECT_NEAR(t.subject_o.row(r).sum(), 1.0, 1e-12);
  }
  EXPECT_EQ(layouts.size(), 2u);      // grids and graphs
  EXPECT_GE(confounders.size(), 5u);  // many numbers of elements
}

// A seed is a task: the same bits every time. Another draw is the same task watched
// again (same MDP, reward and sensor; other demonstrations).
TEST(RandomTask, SameSeedSameTaskAnotherDrawOtherData) {
  const RandomTask a = make_random_task(7, 0);
  const RandomTask b = make_random_task(7, 0);
  const RandomTask c = make_random_task(7, 1);
  EXPECT_EQ(a.true_weights, b.true_weights);
  EXPECT_EQ(a.subject_o, b.subject_o);
  EXPECT_EQ(dataset_digest(a.observed.trajectories), dataset_digest(b.observed.trajectories));
  EXPECT_EQ(a.true_weights, c.true_weights);
  EXPECT_EQ(a.subject_o, c.subject_o);
  EXPECT_NE(dataset_digest(a.observed.trajectories), dataset_digest(c.observed.trajectories));
  EXPECT_THROW(make_random_task(7, -1), InputError);
}

TEST(RandomTask, OverridesFixWhatTheySay) {
  RandomTaskOverrides o;
  o.informativeness = 0.95;
  o.confounders = 2;
  o.occlusion = 0.0;
  o.demonstrations = 6;
  o.eta = "uniform";
  const RandomTask t = make_random_task(3, 0, o);
  EXPECT_EQ(t.informativeness, 0.95);
  EXPECT_EQ(t.num_confounders, 2);
  EXPECT_EQ(t.demonstrations.size(), 6u);
  EXPECT_EQ(t.eta, EtaKind::kUniform);
  for (const auto& obs : t.observed.trajectories) {
    for (int step = 0; step < obs.length(); ++step) EXPECT_EQ(obs.observations_at(step), t.per_step);  // never occluded
  }
  // The controlled run's size alone: the demonstrations and what was seen of them as drawn.
  RandomTaskOverrides bigger;
  bigger.controlled = 40;
  const RandomTask drawn = make_random_task(3, 0), more = make_random_task(3, 0, bigger);
  EXPECT_EQ(more.controlled.size(), 40u);
  EXPECT_NE(drawn.controlled.size(), 40u);
  EXPECT_EQ(more.demonstrations, drawn.demonstrations);
  EXPECT_EQ(more.observed.trajectories[0].symbols, drawn.observed.trajectories[0].symbols);
  EXPECT_EQ(more.end_reports, drawn.end_reports);
  o.eta = "sometimes";
  EXPECT_THROW(make_random_task(3, 0, o), InputError);
}

}  // namespace
}  // namespace hbirl
