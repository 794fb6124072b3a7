#pragma once
// The onion-sorting demonstration from pixels (SPEC §3; paper §Experiments B): the expert
// sorts onions, the simulated camera renders every frame, perception finds the blobs and
// the labeller turns them into observations with eta. The learner gets the observations
// (and, for the True Trajectories baseline and for evaluation, the true steps).
#include <cstdint>
#include <vector>

#include "learner/observations.hpp"
#include "learner/trajectory.hpp"
#include "perception/labeller.hpp"
#include "sim_driver/onion_scene.hpp"

namespace hbirl::onion {

struct OnionDemonstration {
  std::vector<Trajectory> truth;             // the expert's (s, a) steps, one trajectory per sort
  std::vector<bool> blemished;               // the onion of each sort
  std::vector<ObservedTrajectory> observed;  // what perception and the labeller made of the frames
  long long frames = 0;
};

struct DemonstrationOptions {
  int sorts = 10;
  // Onion qualities: alternate good and blemished from a random first one, so any two
  // consecutive sorts show both (the paper: "two trajectories are needed ... to see at
  // least one good and one blemished onion"); false: each sort's onion is blemished
  // with probability `blemished`.
  bool alternate_quality = true;
  double blemished = 0.5;
  bool uniform_eta = false;    // the labeller's Uniform-eta variant
  double start_time = 0.0;     // sim time of the first sort
};

// The labeller's reference sizes for a scene (the gripper's box, an onion's area).
perception::LabellerOptions labeller_options(const SceneConfig& config, bool uniform_eta = false);

// The sorts `demonstrate` renders: the expert's steps and each onion's quality and pose,
// one after another from options.start_time. Same arguments, same sorts.
std::vector<Episode> plan_sorts(const Mdp& mdp, const SceneConfig& config, const DemonstrationOptions& options,
                                std::uint64_t seed);

// Sorts `options.sorts` onions in a scene of `config` and observes them. Same arguments,
// same result.
OnionDemonstration demonstrate(const Mdp& mdp, const SceneConfig& config, const DemonstrationOptions& options,
                               std::uint64_t seed);

// The subject prior of SPEC §3 from a controlled run (the expert alone, true states
// known): for each (s, a), the symbol counts of its observations divided by its number
// of visits -- so the prior weighs as much as one demonstrated step -- plus
// `pseudo_count` everywhere.
Eigen::MatrixXd controlled_prior(const Mdp& mdp, const OnionDemonstration& controlled, double pseudo_count = 1.0);

}  // namespace hbirl::onion
