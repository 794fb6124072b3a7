#include "sim_driver/gridworld/gridworld.hpp"

#include <gtest/gtest.h>

namespace hbirl {
namespace {

TEST(Gridworld, TransitionsFollowSpec) {
  const Mdp mdp = make_gridworld();  // 5x5, intended 0.9
  const double slip = 0.1 / 3.0;
  // Centre cell (2,2) = 12, move up: (1,2) = 7 with 0.9, each other neighbour slip.
  EXPECT_NEAR(mdp.transitions.coeff(mdp.pair(12, 0), 7), 0.9, 1e-15);
  EXPECT_NEAR(mdp.transitions.coeff(mdp.pair(12, 0), 17), slip, 1e-15);
  EXPECT_NEAR(mdp.transitions.coeff(mdp.pair(12, 0), 11), slip, 1e-15);
  EXPECT_NEAR(mdp.transitions.coeff(mdp.pair(12, 0), 13), slip, 1e-15);
  // Top-left corner, move up: off-grid -> stay (0.9), left slip also stays.
  EXPECT_NEAR(mdp.transitions.coeff(mdp.pair(0, 0), 0), 0.9 + slip, 1e-15);
  EXPECT_NEAR(mdp.transitions.coeff(mdp.pair(0, 0), 1), slip, 1e-15);
  EXPECT_NEAR(mdp.transitions.coeff(mdp.pair(0, 0), 5), slip, 1e-15);
  EXPECT_DOUBLE_EQ(mdp.discount, 0.95);
  EXPECT_DOUBLE_EQ(mdp.start[7], 1.0 / 25);
}

TEST(Gridworld, CornerFeatures) {
  const Mdp mdp = make_gridworld();
  EXPECT_EQ(gridworld_corner_state(5, 0), 0);
  EXPECT_EQ(gridworld_corner_state(5, 1), 4);
  EXPECT_EQ(gridworld_corner_state(5, 2), 20);
  EXPECT_EQ(gridworld_corner_state(5, 3), 24);
  EXPECT_EQ(mdp.features.sum(), 16.0);  // 4 corners x 4 actions
  EXPECT_EQ(mdp.features(mdp.pair(24, 2), 3), 1.0);
  EXPECT_EQ(mdp.features(mdp.pair(12, 2), 3), 0.0);
}

TEST(Gridworld, TaskIsSeeded) {
  Rng a(4);
  Rng b(4);
  const GridworldTask x = make_gridworld_task({}, 5, 10, a);
  const GridworldTask y = make_gridworld_task({}, 5, 10, b);
  EXPECT_EQ(x.goal, y.goal);
  EXPECT_EQ(x.trajectories, y.trajectories);
  EXPECT_EQ(x.trajectories.size(), 5u);
  for (const auto& t : x.trajectories) EXPECT_EQ(t.size(), 10u);
  EXPECT_EQ(x.true_weights.sum(), 1.0);
}

}  // namespace
}  // namespace hbirl
