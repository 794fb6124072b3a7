#pragma once
// The simulated camera of the onion-sorting experiment (paper §Experiments B, Fig. 2): an RGB
// view of the expert's blue gripper sorting onions at a conveyor, an inspection spot and
// a bin, with the confounding elements of the paper, each switchable:
//   - a person in a blue shirt (the gripper's colour) walking behind the expert, carrying
//     a tote of the same blue and about the gripper's size,
//   - other onions passing on the conveyor,
//   - a foreground person in an onion-coloured shirt who occludes the expert for stretches,
//   - a mirror on the back wall showing a smaller, reflected view of gripper and onion
//     (the far side of the onion: the expert can still be seen while occluded).
// Blemished onions carry a dark spot on one side: it shows only from some angles, most
// of all while the onion is turned during inspection.
//
// Everything is a function of (config, seed, episode, time): the same arguments give the
// same pixels. Coordinates below are fractions of the frame's width and height.
#include <opencv2/core.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "learner/mdp.hpp"
#include "learner/trajectory.hpp"
#include "perception/camera_view.hpp"
#include "perception/labeller.hpp"

namespace hbirl::onion {

struct SceneConfig {
  int width = 320;  // height = 3/4 of the width
  int fps = 15;
  double step_seconds = 2.0;  // one MDP step
  bool blue_shirt_person = true;
  bool other_onions = true;
  bool foreground_person = true;
  bool mirror = true;
  // The share of the time the foreground person stands in front of the expert (walking in
  // and out counts half), in (0, 0.95]; 0 keeps the default schedule (6 s in front every
  // 16-24 s, about 0.4). `hbirl experiment onion-regimes` sweeps it.
  double foreground_share = 0.0;

  static SceneConfig controlled();  // no confounding elements, no mirror
  // "controlled", "all", or a comma-separated list of blue-shirt, other-onions,
  // foreground, mirror (the rest of the fields at their defaults). Throws
  // InputError(field, ...) naming an unknown element.
  static SceneConfig parse(const std::string& elements, const std::string& field = "config");
  std::string elements() const;  // the inverse: "controlled", "all" or the list
  int height() const;            // 3/4 of the width (camera_view)
  int frames_per_step() const;
  // Throws InputError naming the first bad field.
  void validate() const;
};

// One demonstrated sort: the expert's (s, a) steps, the onion's true quality and how it
// lies, and when the sort began (sim seconds; the confounders move on a global clock).
struct Episode {
  Trajectory steps;
  bool blemished = false;
  double onion_angle = 0.0;  // how the onion lies on the belt (radians)
  double spot_angle = 0.0;   // where its blemish is
  double start_time = 0.0;
};

// What the scene's camera shows, as shares of the frame: the labeller's reference sizes
// (the onion domain states it, Domain::camera).
perception::CameraView camera_view();
// The gripper's appearance at this resolution (the labeller's reference size).
using GripperSize = perception::PixelBox;
GripperSize gripper_size(const SceneConfig& config);
// An onion's area in pixels at this resolution.
double onion_area(const SceneConfig& config);

class OnionScene {
 public:
  OnionScene(const SceneConfig& config, std::uint64_t seed);

  // Frame `frame` (0 .. frames_per_step - 1) of step t of the episode, BGR 8-bit.
  void render(const Episode& episode, int t, int frame, cv::Mat& out) const;
  // The sim time of that frame.
  double time_of(const Episode& episode, int t, int frame) const;

  const SceneConfig& config() const { return config_; }

 private:
  struct Pose {
    double gx, gy;       // gripper centre
    double ox, oy;       // onion centre
    double onion_angle;  // onion rotation
    bool onion_visible;
    bool onion_in_bin;  // drawn behind the bin's front
  };
  Pose pose(const Episode& episode, int t, double u) const;
  void draw_background(cv::Mat& img) const;
  void draw_mirror(cv::Mat& img, const Pose& p, const Episode& e) const;
  void draw_blue_person(cv::Mat& img, double time) const;
  void draw_other_onions(cv::Mat& img, double time) const;
  void draw_expert(cv::Mat& img, const Pose& p, const Episode& e) const;
  void draw_foreground_person(cv::Mat& img, double time) const;
  void draw_onion(cv::Mat& img, double x, double y, double radius, double angle, double spot, bool blemished) const;

  SceneConfig config_;
  std::uint64_t seed_;
  double walk_phase_;  // blue-shirt person
  double walk_period_;
  double occlusion_phase_;  // foreground person
  double occlusion_period_;
  double occlusion_stay_ = 6.0;                  // seconds in front of the expert per period
  static constexpr double kOcclusionWalk = 1.5;  // seconds to walk in (and out)
  cv::Mat background_;
};

// A sort's episode for the scene: the expert's trajectory and a random onion pose.
Episode make_episode(const Trajectory& steps, bool blemished, double start_time, std::uint64_t seed);

struct DemonstrationOptions {
  int sorts = 10;
  // Onion qualities: alternate good and blemished from a random first one, so any two
  // consecutive sorts show both (the paper: "two trajectories are needed ... to see at
  // least one good and one blemished onion"); false: each sort's onion is blemished
  // with probability `blemished`.
  bool alternate_quality = true;
  double blemished = 0.5;
  bool uniform_eta = false;  // the labeller's Uniform-eta variant (labeller_options)
  double start_time = 0.0;   // sim time of the first sort
  // Give each observation the labeller's rule as its context, as the labeller service
  // does (perception/labeller.hpp); off, each distinct eta is a context (the experiments).
  bool rule_contexts = false;
};

// The sorts a demonstration renders: the expert's steps and each onion's quality and
// pose, one after another from options.start_time. Same arguments, same sorts.
std::vector<Episode> plan_sorts(const Mdp& mdp, const SceneConfig& config, const DemonstrationOptions& options,
                                std::uint64_t seed);

// The labeller's options for this scene's frames (perception::labeller_options of its camera_view()).
perception::LabellerOptions labeller_options(const SceneConfig& config, bool uniform_eta = false);

}  // namespace hbirl::onion
