#include "sim_driver/gridworld/gridworld.hpp"

#include <stdexcept>

#include "learner/input_error.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl {

namespace {
constexpr int kMoves[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};  // up, down, left, right
}

int gridworld_corner_state(int size, int corner) {
  const int row = (corner / 2) * (size - 1);
  const int col = (corner % 2) * (size - 1);
  return row * size + col;
}

Mdp make_gridworld(const GridworldOptions& options) {
  const int n = options.size;
  if (n < 2) throw InputError("size", "gridworld needs at least 2 x 2 cells");
  if (!(options.intended >= 0.0 && options.intended <= 1.0)) {
    throw InputError("intended", "must be a probability");
  }
  const int S = n * n;
  std::vector<TransitionEntry> transitions;
  const double slip = (1.0 - options.intended) / 3.0;
  for (int s = 0; s < S; ++s) {
    const int row = s / n;
    const int col = s % n;
    for (int a = 0; a < 4; ++a) {
      for (int m = 0; m < 4; ++m) {
        const double p = m == a ? options.intended : slip;
        if (p == 0.0) continue;
        int r2 = row + kMoves[m][0];
        int c2 = col + kMoves[m][1];
        if (r2 < 0 || r2 >= n || c2 < 0 || c2 >= n) {
          r2 = row;
          c2 = col;
        }
        transitions.push_back({s, a, r2 * n + c2, p});  // duplicates are summed
      }
    }
  }
  std::vector<FeatureEntry> features;
  for (int k = 0; k < 4; ++k) {
    for (int a = 0; a < 4; ++a) features.push_back({gridworld_corner_state(n, k), a, k, 1.0});
  }
  const Eigen::VectorXd start = Eigen::VectorXd::Constant(S, 1.0 / S);
  Mdp mdp = make_mdp(S, 4, 4, transitions, features, start, {}, options.discount);
  mdp.validate();
  return mdp;
}

std::vector<std::string> gridworld_state_names(int size) {
  std::vector<std::string> names;
  for (int s = 0; s < size * size; ++s) {
    names.push_back("r" + std::to_string(s / size) + "c" + std::to_string(s % size));
  }
  return names;
}

std::vector<std::string> gridworld_action_names() { return {"up", "down", "left", "right"}; }

std::vector<std::string> gridworld_feature_names() { return {"top_left", "top_right", "bottom_left", "bottom_right"}; }

std::vector<Trajectory> soft_expert_demonstration(const Mdp& mdp, const Eigen::VectorXd& weights, int num_trajectories,
                                                  int length, Rng& rng) {
  const SoftSolution expert = soft_value_iteration(mdp, mdp.reward(weights));
  if (!expert.converged) throw std::runtime_error("soft value iteration did not converge");
  std::vector<Trajectory> trajectories;
  for (int i = 0; i < num_trajectories; ++i) {
    trajectories.push_back(sample_trajectory(mdp, expert.policy, length, rng));
  }
  return trajectories;
}

GridworldTask make_gridworld_task(const GridworldOptions& options, int num_trajectories, int length, Rng& rng) {
  GridworldTask task;
  task.mdp = make_gridworld(options);
  task.goal = rng.uniform_int(4);
  task.true_weights = Eigen::VectorXd::Zero(4);
  task.true_weights[task.goal] = 1.0;
  task.trajectories = soft_expert_demonstration(task.mdp, task.true_weights, num_trajectories, length, rng);
  return task;
}

}  // namespace hbirl
