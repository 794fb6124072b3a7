#include "sim_driver/onion/onion.hpp"

#include "learner/input_error.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl::onion {

State next_state(const State& s, int action, int inspected) {
  State n = s;
  switch (action) {
    case kGrip:
      if (s.onion == kOnConveyor && s.gripper == kAtConveyor) n.onion = kGripped;
      break;
    case kRelease:
      if (s.onion == kGripped && s.gripper == kAtConveyor) n.onion = kOnConveyor;
      if (s.onion == kGripped && s.gripper == kAtBin) n.onion = kInBin;
      break;
    case kInspect:
      if (s.onion == kGripped && s.gripper == kAtInspection && s.quality == kUnknown) n.quality = inspected;
      break;
    case kMoveToConveyor:
      n.gripper = kAtConveyor;
      break;
    case kMoveToInspection:
      n.gripper = kAtInspection;
      break;
    case kMoveToBin:
      n.gripper = kAtBin;
      break;
    default:
      throw InputError("action", "unknown onion action " + std::to_string(action));
  }
  return n;
}

bool is_terminal(const State& s) { return s.onion == kInBin || (s.onion == kOnConveyor && s.quality != kUnknown); }

Mdp make_onion_mdp(const OnionOptions& options) {
  if (!(options.blemished > 0.0 && options.blemished < 1.0)) throw InputError("blemished", "must be in (0, 1)");
  std::vector<TransitionEntry> transitions;
  std::vector<FeatureEntry> features;
  std::vector<int> terminal;
  Eigen::VectorXd start = Eigen::VectorXd::Zero(kNumStates);
  for (int s = 0; s < kNumStates; ++s) {
    const State st = state(s);
    if (is_terminal(st)) {
      terminal.push_back(s);
      continue;
    }
    if (st.quality == kUnknown && st.onion == kOnConveyor) start[s] = 1.0 / 3.0;
    for (int a = 0; a < kNumActions; ++a) {
      const State good = next_state(st, a, kGood);
      const State bad = next_state(st, a, kBlemished);
      if (good == bad) {
        transitions.push_back({s, a, index(good), 1.0});
      } else {
        transitions.push_back({s, a, index(good), 1.0 - options.blemished});
        transitions.push_back({s, a, index(bad), options.blemished});
      }
    }
    if (st.onion == kGripped && st.quality != kUnknown && st.gripper != kAtInspection) {
      const bool good = st.quality == kGood;
      const bool bin = st.gripper == kAtBin;
      const int k = good ? (bin ? kGoodInBin : kGoodOnConveyor) : (bin ? kBlemishedInBin : kBlemishedOnConveyor);
      features.push_back({s, kRelease, k, 1.0});
    }
  }
  Mdp mdp = make_mdp(kNumStates, kNumActions, kNumFeatures, transitions, features, start, terminal, options.discount);
  mdp.validate();
  return mdp;
}

std::vector<std::string> state_names() {
  static const char* quality[] = {"unknown", "good", "blemished"};
  static const char* onion[] = {"on_conveyor", "gripped", "in_bin"};
  static const char* gripper[] = {"conveyor", "inspection", "bin"};
  std::vector<std::string> names;
  for (int s = 0; s < kNumStates; ++s) {
    const State st = state(s);
    names.push_back(std::string(quality[st.quality]) + "/" + onion[st.onion] + "/" + gripper[st.gripper]);
  }
  return names;
}

std::vector<std::string> action_names() {
  return {"grip", "release", "inspect", "move_to_conveyor", "move_to_inspection", "move_to_bin"};
}

std::vector<std::string> feature_names() {
  return {"release_good_in_bin", "release_good_on_conveyor", "release_blemished_in_bin",
          "release_blemished_on_conveyor"};
}

Eigen::VectorXd expert_weights() {
  Eigen::VectorXd w(kNumFeatures);
  w[kGoodInBin] = -1.0;
  w[kGoodOnConveyor] = 1.0;
  w[kBlemishedInBin] = 1.0;
  w[kBlemishedOnConveyor] = -1.0;
  return w;
}

ControlledPriorOptions controlled_prior_options() {
  ControlledPriorOptions o;
  o.pseudo_count = 1.0;
  o.per_visit = true;
  return o;
}

Trajectory expert_sort(const Mdp& mdp, const Eigen::VectorXd& weights, int gripper_start, bool blemished,
                       int max_steps) {
  const std::vector<int> policy = value_iteration(mdp, mdp.reward(weights)).actions;
  Trajectory out;
  State s{kUnknown, kOnConveyor, gripper_start};
  for (int step = 0; step < max_steps && !is_terminal(s); ++step) {
    const int a = policy[static_cast<size_t>(index(s))];
    out.push_back({index(s), a});
    s = next_state(s, a, blemished ? kBlemished : kGood);
  }
  return out;
}

}  // namespace hbirl::onion
