#pragma once
// The paper's Gridworld (paper §Experiments A): an n x n grid, 4 moves, the intended move
// succeeds with probability `intended`, otherwise the agent lands in one of the other
// three moves' cells (equally likely); a move off the grid stays put. Reward features:
// being in each of the 4 corners. No terminal states; uniform start.
//
// State s = row * n + col, row 0 at the top. Actions: 0 up, 1 down, 2 left, 3 right.
// Corners (features): 0 top-left, 1 top-right, 2 bottom-left, 3 bottom-right.
#include <string>
#include <vector>

#include "learner/mdp.hpp"
#include "learner/rng.hpp"
#include "learner/trajectory.hpp"

namespace hbirl {

struct GridworldOptions {
  int size = 5;
  double intended = 0.9;
  double discount = 0.95;
};

Mdp make_gridworld(const GridworldOptions& options = {});

int gridworld_corner_state(int size, int corner);
std::vector<std::string> gridworld_state_names(int size);
std::vector<std::string> gridworld_action_names();
std::vector<std::string> gridworld_feature_names();

// A learning task: the MDP, a goal corner drawn at random (weight 1, others 0) and
// `num_trajectories` demonstrations of `length` steps from the soft expert (docs/MODEL.md "The expert").
struct GridworldTask {
  Mdp mdp;
  int goal = 0;
  Eigen::VectorXd true_weights;
  std::vector<Trajectory> trajectories;
};

GridworldTask make_gridworld_task(const GridworldOptions& options, int num_trajectories, int length, Rng& rng);

// The soft expert's demonstration for given weights (used by the task above).
std::vector<Trajectory> soft_expert_demonstration(const Mdp& mdp, const Eigen::VectorXd& weights, int num_trajectories,
                                                  int length, Rng& rng);

}  // namespace hbirl
