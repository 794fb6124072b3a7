#pragma once
// Which observations could have been made at all: the support of the model (docs/MODEL.md
// "Impossible data"). An observation no source can produce at any state-action its
// trajectory can be in has probability 0 under every reward, and EM would learn nothing
// from the data set (every weight 0). Checked before learning, so that the answer is one
// line naming the observation instead of a reward of zeros.
#include <optional>
#include <string>
#include <vector>

#include "learner/mdp.hpp"
#include "learner/observations.hpp"

namespace hbirl {

struct ImpossibleObservation {
  int trajectory = 0;
  int step = 0;
  int observation = -1;  // within the step; -1: no single one, the step's observations together
  std::string why;
};

// The first observation (trajectory, step, observation) that no source can produce given
// the states the trajectory can reach: the subject only where its prior alpha is positive
// at a reachable (state, action), a confounding element only where its alpha is positive,
// each only when the observation's eta gives it weight. The support does not depend on
// the reward (every possible action has positive soft-policy probability) nor on learning
// (alpha only grows where the posterior puts mass, eta keeps its zeros), so this is exact.
std::optional<ImpossibleObservation> first_impossible_observation(const Mdp& mdp,
                                                                  const std::vector<ObservedTrajectory>& trajectories,
                                                                  const ObservationPrior& prior);

}  // namespace hbirl
