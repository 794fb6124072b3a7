#include "sim_driver/onion/onion.hpp"

#include <gtest/gtest.h>

#include "learner/value_iteration.hpp"

namespace hbirl::onion {
namespace {

// The onion-sorting transition table (paper §Experiments B; docs/MODEL.md "The onion-sorting domain"),
// action by action, against hand-written expectations.
TEST(OnionMdp, TransitionTable) {
  const Mdp mdp = make_onion_mdp({0.3, 0.95});
  auto p = [&](const State& s, int a, const State& next) {
    return mdp.transitions.coeff(mdp.pair(index(s), a), index(next));
  };
  const State start{kUnknown, kOnConveyor, kAtConveyor};
  EXPECT_EQ(p(start, kGrip, {kUnknown, kGripped, kAtConveyor}), 1.0);
  EXPECT_EQ(p({kUnknown, kOnConveyor, kAtBin}, kGrip, {kUnknown, kOnConveyor, kAtBin}),
            1.0);  // not at the conveyor: no effect
  EXPECT_EQ(p({kUnknown, kGripped, kAtConveyor}, kMoveToInspection, {kUnknown, kGripped, kAtInspection}), 1.0);
  EXPECT_DOUBLE_EQ(p({kUnknown, kGripped, kAtInspection}, kInspect, {kGood, kGripped, kAtInspection}), 0.7);
  EXPECT_DOUBLE_EQ(p({kUnknown, kGripped, kAtInspection}, kInspect, {kBlemished, kGripped, kAtInspection}), 0.3);
  EXPECT_EQ(p({kUnknown, kGripped, kAtConveyor}, kInspect, {kUnknown, kGripped, kAtConveyor}),
            1.0);  // only at inspection
  EXPECT_EQ(p({kGood, kGripped, kAtInspection}, kInspect, {kGood, kGripped, kAtInspection}), 1.0);  // already known
  EXPECT_EQ(p({kGood, kGripped, kAtBin}, kRelease, {kGood, kInBin, kAtBin}), 1.0);
  EXPECT_EQ(p({kBlemished, kGripped, kAtConveyor}, kRelease, {kBlemished, kOnConveyor, kAtConveyor}), 1.0);
  EXPECT_EQ(p({kGood, kGripped, kAtInspection}, kRelease, {kGood, kGripped, kAtInspection}), 1.0);  // no effect
  EXPECT_EQ(p({kUnknown, kOnConveyor, kAtConveyor}, kMoveToBin, {kUnknown, kOnConveyor, kAtBin}), 1.0);
  // Terminal: the onion in the bin, or back on the belt once its quality is known.
  EXPECT_TRUE(mdp.is_terminal(index({kGood, kInBin, kAtBin})));
  EXPECT_TRUE(mdp.is_terminal(index({kBlemished, kOnConveyor, kAtConveyor})));
  EXPECT_FALSE(mdp.is_terminal(index({kUnknown, kOnConveyor, kAtConveyor})));
  EXPECT_FALSE(mdp.is_terminal(index({kGood, kGripped, kAtBin})));
  // Features: only releasing an inspected onion at the conveyor or the bin.
  EXPECT_EQ(mdp.features(mdp.pair(index({kGood, kGripped, kAtConveyor}), kRelease), kGoodOnConveyor), 1.0);
  EXPECT_EQ(mdp.features(mdp.pair(index({kBlemished, kGripped, kAtBin}), kRelease), kBlemishedInBin), 1.0);
  EXPECT_EQ(mdp.features.sum(), 4.0);
  EXPECT_NEAR(mdp.start.sum(), 1.0, 1e-15);
}

// The expert keeps good onions and bins blemished ones, in 5 steps from the conveyor and
// 6 from elsewhere, each sort ending on release.
TEST(OnionMdp, ExpertSortsAsTheSpecSays) {
  const Mdp mdp = make_onion_mdp();
  for (int gripper : {kAtConveyor, kAtInspection, kAtBin}) {
    for (bool blemished : {false, true}) {
      const Trajectory sort = expert_sort(mdp, expert_weights(), gripper, blemished);
      ASSERT_EQ(static_cast<int>(sort.size()), gripper == kAtConveyor ? 5 : 6);
      EXPECT_EQ(sort.back().action, kRelease);
      const State last = state(sort.back().state);
      EXPECT_EQ(last.quality, blemished ? kBlemished : kGood);
      EXPECT_EQ(last.gripper, blemished ? kAtBin : kAtConveyor);
      EXPECT_TRUE(std::any_of(sort.begin(), sort.end(), [](const StateAction& x) { return x.action == kInspect; }));
    }
  }
}

}  // namespace
}  // namespace hbirl::onion
