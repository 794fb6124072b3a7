#pragma once
// The onion-sorting demonstration from pixels (paper §Experiments B; docs/onion-camera.md): the expert
// sorts onions, the simulated camera renders every frame, perception finds the blobs and
// the labeller turns them into observations with eta. The learner gets the observations
// (and, for the True Trajectories baseline and for evaluation, the true steps).
#include <cstdint>
#include <vector>

#include "learner/observations.hpp"
#include "learner/trajectory.hpp"
#include "sim_driver/onion/scene.hpp"

namespace hbirl::onion {

struct OnionDemonstration {
  std::vector<Trajectory> truth;             // the expert's (s, a) steps, one trajectory per sort
  std::vector<bool> blemished;               // the onion of each sort
  std::vector<ObservedTrajectory> observed;  // what perception and the labeller made of the frames
  long long frames = 0;
};

// Sorts `options.sorts` onions in a scene of `config` and observes them. Same arguments,
// same result.
OnionDemonstration demonstrate(const Mdp& mdp, const SceneConfig& config, const DemonstrationOptions& options,
                               std::uint64_t seed);

}  // namespace hbirl::onion
