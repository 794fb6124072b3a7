#pragma once
// The subject's prior from a controlled run: the expert alone in front of the sensor, its
// true (s, a) known at every step, so every observation is the subject's (paper §III,
// "Controlled Environments"; docs/MODEL.md "The observation model: what is learned, and why").
// The one place every domain, the experiments and the services build it.
#include <vector>

#include <Eigen/Dense>

#include "learner/mdp.hpp"
#include "learner/observations.hpp"
#include "learner/trajectory.hpp"

namespace hbirl {

struct ControlledPriorOptions {
  double pseudo_count = 1.0;  // added to every (s, a, symbol): the prior's base
  // Divide each (s, a)'s counts by its number of visits, so that the controlled run
  // weighs as much as one step per pair however long it ran (the onion's choice,
  // docs/MODEL.md "The onion-sorting domain"); false: the counts as observed.
  bool per_visit = false;
};

// alpha(pair(s, a), w) = pseudo_count + the observations of symbol w (with their
// multiplicities) at the controlled steps in (s, a) [/ visits of (s, a)]. `truth[i]` and
// `observed[i]` are one episode. Throws InputError naming "ground_truth" for a trajectory
// count or length that differs, or a state or action outside the MDP,
// "observations.symbols" for a symbol outside [0, num_symbols), and
// "observations.step_begin" / "observations.weights" for a malformed layout.
Eigen::MatrixXd controlled_run_prior(const Mdp& mdp, const std::vector<Trajectory>& truth,
                                     const std::vector<ObservedTrajectory>& observed, int num_symbols,
                                     const ControlledPriorOptions& options = {});

}  // namespace hbirl
