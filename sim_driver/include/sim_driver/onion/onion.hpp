#pragma once
// The paper's onion-sorting domain (paper §Experiments B; docs/MODEL.md "The onion-sorting domain").
//
// State = (onion quality, onion position, gripper position), 3 x 3 x 3 = 27 states,
//   s = quality * 9 + onion * 3 + gripper
//   quality  0 unknown, 1 good, 2 blemished
//   onion    0 on the conveyor, 1 gripped, 2 in the bin
//   gripper  0 at the conveyor, 1 at the inspection spot, 2 at the bin
// Actions (no effect where not applicable):
//   grip     on the conveyor -> gripped, when the gripper is at the conveyor
//   release  gripped -> on the conveyor or in the bin, by the gripper's position (no
//            effect at the inspection spot)
//   inspect  quality unknown -> good or blemished (probability `blemished`), when the
//            onion is gripped at the inspection spot
//   move to conveyor / inspection / bin: the gripper (and a gripped onion) goes there.
// Features (4): releasing a good / blemished onion in the bin / on the conveyor.
//
// How a sort ends: releasing the onion ends the trajectory. States with the onion in the
// bin, or back on the conveyor with its quality known, are terminal; releasing an
// uninspected onion onto the conveyor puts it back where a sort starts. Trajectories
// start with an uninspected onion on the conveyor and the gripper anywhere, so the
// expert's sorts take 5 steps (gripper at the conveyor) or 6.
#include <string>
#include <vector>

#include "learner/controlled_prior.hpp"
#include "learner/mdp.hpp"
#include "learner/rng.hpp"
#include "learner/trajectory.hpp"

namespace hbirl::onion {

enum Quality { kUnknown = 0, kGood = 1, kBlemished = 2 };
enum OnionAt { kOnConveyor = 0, kGripped = 1, kInBin = 2 };
enum GripperAt { kAtConveyor = 0, kAtInspection = 1, kAtBin = 2 };
enum Action { kGrip = 0, kRelease = 1, kInspect = 2, kMoveToConveyor = 3, kMoveToInspection = 4, kMoveToBin = 5 };
enum Feature { kGoodInBin = 0, kGoodOnConveyor = 1, kBlemishedInBin = 2, kBlemishedOnConveyor = 3 };

constexpr int kNumStates = 27;
constexpr int kNumActions = 6;
constexpr int kNumFeatures = 4;

struct State {
  int quality = kUnknown;
  int onion = kOnConveyor;
  int gripper = kAtConveyor;
  friend bool operator==(const State&, const State&) = default;
};

inline int index(const State& s) { return s.quality * 9 + s.onion * 3 + s.gripper; }
inline State state(int s) { return {s / 9, (s / 3) % 3, s % 3}; }

// The state an action leads to; `inspected` is the quality an inspection reveals.
State next_state(const State& s, int action, int inspected);
bool is_terminal(const State& s);

struct OnionOptions {
  double blemished = 0.5;  // probability that an inspected onion is blemished
  double discount = 0.95;
};

Mdp make_onion_mdp(const OnionOptions& options = {});

std::vector<std::string> state_names();
std::vector<std::string> action_names();
std::vector<std::string> feature_names();

// The expert's reward: keep good onions on the conveyor, bin blemished ones.
Eigen::VectorXd expert_weights();

// How the subject prior is built from the controlled run: counts per visit plus 1, so
// that the run weighs as much as one demonstrated step per (s, a) (docs/MODEL.md "The
// onion-sorting domain").
ControlledPriorOptions controlled_prior_options();

// One sort by the expert: the optimal policy of `weights` from an uninspected onion on
// the conveyor with the gripper at `gripper_start`, for an onion that is blemished or not.
// Ends when the onion is released (or after `max_steps`).
Trajectory expert_sort(const Mdp& mdp, const Eigen::VectorXd& weights, int gripper_start, bool blemished,
                       int max_steps = 12);

}  // namespace hbirl::onion
