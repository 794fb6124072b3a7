#pragma once
// Planning for a known reward with the hard (max) Bellman equation, and exact policy
// evaluation -- the tools the ILE metric needs.
#include <vector>

#include "learner/mdp.hpp"

namespace hbirl {

struct OptimalPolicy {
  Eigen::VectorXd value;      // V*(s), 0 at terminal states
  Eigen::VectorXd q;          // Q*(s,a) per pair, -inf where impossible or terminal
  std::vector<int> actions;   // a greedy action per state (lowest index among ties); -1 at terminals
  int iterations = 0;         // value-iteration sweeps (Gauss-Seidel, self-loops solved)
  int policy_iterations = 0;  // exact evaluate-and-improve rounds after value iteration
};

// Value iteration (Gauss-Seidel sweeps that solve each action's self-loop) to
// max|dV| <= tolerance * max(1, max|V|) in a sweep, then policy iteration
// (exact evaluation + improvement that only switches on a strict gain) so the returned
// policy is optimal, not merely near-optimal.
OptimalPolicy value_iteration(const Mdp& mdp, const Eigen::VectorXd& reward, double tolerance = 1e-10);

// V^pi for the reward: solves (I - gamma P_pi) V = R_pi exactly (up to the linear
// solver's 1e-14 relative tolerance). Deterministic policy: one action per state.
// `guess`: where the iterative solver starts (a nearby policy's value saves most of its
// iterations); none: from R_pi.
Eigen::VectorXd policy_evaluation(const Mdp& mdp, const Eigen::VectorXd& reward, const std::vector<int>& actions,
                                  const Eigen::VectorXd* guess = nullptr);
// Stochastic policy: one probability per (s, a) pair.
Eigen::VectorXd policy_evaluation(const Mdp& mdp, const Eigen::VectorXd& reward, const Eigen::VectorXd& policy,
                                  const Eigen::VectorXd* guess = nullptr);

}  // namespace hbirl
