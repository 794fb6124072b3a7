#pragma once
// How a domain's simulator runs (sim_driver/registry/domain.hpp, Domain::simulate): one
// struct the simulator service's command line fills, of which each domain's simulator
// reads what concerns it. The one header of the registry that knows the built-in
// simulators' own options (the onion scene's, the Gridworld sensor's eta).
#include <cstdint>

#include "sim_driver/gridworld/observations.hpp"
#include "sim_driver/onion/scene.hpp"

namespace hbirl {

struct SimulationOptions {
  std::uint64_t seed = 1;
  // onion: the demonstrations' scene, sorts in the controlled scene, then demonstrated
  onion::SceneConfig scene;
  int controlled_sorts = 20;
  int sorts = 6;
  // gridworld: the paper's sensor
  int confounders = 3;               // |E|
  int per_step = 40;                 // observations per step, drawn equally from the subject and each element
  int trajectories = 20;             // demonstrations
  int controlled_trajectories = 20;  // controlled run: the subject alone, true states known
  int length = 10;                   // steps per trajectory
  EtaKind eta = EtaKind::kPlausible;
  double step_seconds = 1.0;  // sim time per step
};

}  // namespace hbirl
