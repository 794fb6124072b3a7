#pragma once
// Trajectories X = ((s,a)_1 ... (s,a)_T) and what is computed straight from them.
#include <vector>

#include "learner/mdp.hpp"
#include "learner/rng.hpp"

namespace hbirl {

struct StateAction {
  int state;
  int action;
  friend bool operator==(const StateAction&, const StateAction&) = default;
};

using Trajectory = std::vector<StateAction>;

// Samples up to `length` steps from the start distribution under `policy` (one
// probability per (s, a) pair). Stops early when the next state is terminal; then
// *entered_terminal (when given) is set true, else false, and *entered_state (when given)
// to that state, else -1.
Trajectory sample_trajectory(const Mdp& mdp, const Eigen::VectorXd& policy, int length, Rng& rng,
                             bool* entered_terminal = nullptr, int* entered_state = nullptr);

// The probability that a trajectory sample_trajectory draws enters a terminal state within
// `length` steps, computed exactly: the start distribution carried forward under `policy`,
// the mass that enters a terminal state taken out at each step.
double probability_of_ending_within(const Mdp& mdp, const Eigen::VectorXd& policy, int length);

// N(s,a): how often each pair is visited, one entry per pair.
Eigen::VectorXd visit_counts(const Mdp& mdp, const std::vector<Trajectory>& trajectories);

}  // namespace hbirl
