#include "sim_driver/onion/scene.hpp"

#include <gtest/gtest.h>

#include "learner/input_error.hpp"
#include "perception/blobs.hpp"
#include "perception/labeller.hpp"
#include "sim_driver/onion/onion.hpp"

namespace hbirl::onion {
namespace {

Episode sort_episode(int gripper_start, bool blemished, std::uint64_t seed) {
  const Mdp mdp = make_onion_mdp();
  return make_episode(expert_sort(mdp, expert_weights(), gripper_start, blemished), blemished, 3.0, seed);
}

TEST(OnionScene, SameSeedSamePixels) {
  const Episode e = sort_episode(kAtBin, true, 5);
  const OnionScene a(SceneConfig{}, 9), b(SceneConfig{}, 9);
  cv::Mat x, y;
  for (int t = 0; t < static_cast<int>(e.steps.size()); ++t) {
    a.render(e, t, 7, x);
    b.render(e, t, 7, y);
    ASSERT_EQ(cv::norm(x, y, cv::NORM_INF), 0.0) << "step " << t;
  }
}

// In the controlled scene perception sees the expert alone: one gripper blob per frame,
// at the start of each step in the region of the gripper's position.
TEST(OnionScene, ControlledSceneShowsOnlyTheExpert) {
  const SceneConfig config = SceneConfig::controlled();
  const OnionScene scene(config, 1);
  perception::BlobDetector detector;
  const int region_of[3] = {perception::gripper_region(0.24 * 320, 0.70 * 240, 320, 240),
                            perception::gripper_region(0.50 * 320, 0.45 * 240, 320, 240),
                            perception::gripper_region(0.82 * 320, 0.60 * 240, 320, 240)};
  cv::Mat frame;
  for (int start : {kAtConveyor, kAtBin}) {
    const Episode e = sort_episode(start, start == kAtBin, 2);
    for (int t = 0; t < static_cast<int>(e.steps.size()); ++t) {
      const State s = state(e.steps[static_cast<size_t>(t)].state);
      for (int k = 0; k < config.frames_per_step(); k += 3) {
        scene.render(e, t, k, frame);
        int grippers = 0, onions = 0;
        for (const auto& d : detector.detect(frame)) {
          if (d.cls == perception::BlobClass::kGripper) {
            ++grippers;
            if (k == 0) {
              EXPECT_EQ(perception::gripper_region(d.x, d.y, 320, 240), region_of[s.gripper]) << "step " << t;
            }
          } else {
            ++onions;
          }
        }
        EXPECT_EQ(grippers, 1) << "step " << t << " frame " << k;
        EXPECT_LE(onions, 1) << "step " << t << " frame " << k;
      }
    }
  }
}

// A blemished onion shows its dark side in some frames of its inspection and not in others;
// a good onion never looks dark.
TEST(OnionScene, BlemishesShowFromSomeAnglesOnly) {
  const SceneConfig config = SceneConfig::controlled();
  const OnionScene scene(config, 1);
  perception::BlobDetector detector;
  perception::LabellerOptions labels;
  labels.gripper_area = 22.0 * 16.0;
  labels.onion_area = onion_area(config);
  cv::Mat frame;
  for (bool blemished : {false, true}) {
    const Episode e = sort_episode(kAtConveyor, blemished, 4);
    const int inspect = 2;  // grip, move to inspection, inspect, ...
    ASSERT_EQ(e.steps[inspect].action, kInspect);
    int dark = 0, bright = 0;
    for (int k = 0; k < config.frames_per_step(); ++k) {
      scene.render(e, inspect, k, frame);
      for (const auto& o : perception::label(detector.detect(frame), labels)) {
        dark += o.symbol == perception::kDarkOnion;
        bright += o.symbol == perception::kBrightOnion;
      }
    }
    if (blemished) {
      EXPECT_GT(dark, 0);
      EXPECT_GT(bright, 0);
    } else {
      EXPECT_EQ(dark, 0);
      EXPECT_EQ(bright, config.frames_per_step());
    }
  }
}

TEST(SceneConfig, ParsesElementLists) {
  EXPECT_EQ(SceneConfig::parse("controlled").elements(), "controlled");
  EXPECT_EQ(SceneConfig::parse("all").elements(), "all");
  const SceneConfig c = SceneConfig::parse("mirror,blue-shirt");
  EXPECT_TRUE(c.mirror && c.blue_shirt_person && !c.other_onions && !c.foreground_person);
  EXPECT_EQ(c.elements(), "blue-shirt,mirror");
  EXPECT_EQ(SceneConfig::parse("blue-shirt,other-onions,foreground,mirror").elements(), "all");
  try {
    SceneConfig::parse("mirror,dog", "--config");
    FAIL() << "accepted an unknown element";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--config"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'dog'"), std::string::npos) << e.what();
  }
}

TEST(OnionScene, RejectsBadConfigs) {
  SceneConfig c;
  c.width = 10;
  EXPECT_THROW(OnionScene(c, 1), InputError);
  c = SceneConfig{};
  c.fps = 0;
  EXPECT_THROW(OnionScene(c, 1), InputError);
}

}  // namespace
}  // namespace hbirl::onion
