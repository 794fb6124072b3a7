#pragma once
// From detections to the paper's observations and their source distributions eta
// (paper §Experiments B and appendix; docs/onion-camera.md "The onion camera").
//
// Alphabet Omega (22 symbols): a gripper-coloured blob is one of 20 equal regions of the
// field of view (5 columns x 4 rows, row-major from the top left), by its centroid; an
// onion-coloured blob is Bright (20) or Dark (21) by its share of dark pixels.
//
// Sources: 0 the subject (the expert), 1 the person in the blue shirt, 2 the other
// onions, 3 the foreground person.
//   gripper blob: eta(subject) grows as the blob's size approaches the gripper's known
//     size, r = min(area, A) / max(area, A) with A the gripper's bounding-box area; the
//     rest goes to the blue-shirt person.
//   onion blob near a gripper blob: 0.8 subject, 0.1 other onions, 0.1 foreground person.
//   onion blob not near one: 0.6 to the other onions if small, to the foreground person if
//     large; 0.1 subject; 0.25 the other of those two; the remaining 0.05 to the
//     blue-shirt person.
// eta's subject share is rounded to 0.05 (and kept in [0.05, 0.95]): the labeller's
// estimate is coarse by nature, and few distinct eta make the E-step cheap.
//
// Each observation also says which rule gave its eta (its context for learned eta,
// docs/MODEL.md "Learned eta"): the gripper rule once per size ratio r = 0.05 .. 0.95
// (contexts 0 .. 18: each ratio is its own claim), then the three onion rules. With the
// Uniform-eta variant the rules still fire: learned eta then finds each rule's
// calibration from a flat start.
#include <array>
#include <vector>

#include "perception/blobs.hpp"
#include "perception/camera_view.hpp"

namespace hbirl::perception {

constexpr int kRegionColumns = 5;
constexpr int kRegionRows = 4;
constexpr int kBrightOnion = kRegionColumns * kRegionRows;  // 20
constexpr int kDarkOnion = kBrightOnion + 1;                // 21
constexpr int kNumSymbols = kDarkOnion + 1;                 // 22
constexpr int kNumSources = 4;
enum Source { kSubject = 0, kBlueShirtPerson = 1, kOtherOnions = 2, kForegroundPerson = 3 };

constexpr int kGripperRatioRules = 19;                      // r = 0.05, 0.10, .., 0.95
constexpr int kOnionNearGripperRule = kGripperRatioRules;   // 19
constexpr int kLargeOnionRule = kOnionNearGripperRule + 1;  // 20
constexpr int kSmallOnionRule = kLargeOnionRule + 1;        // 21
constexpr int kNumRules = kSmallOnionRule + 1;              // 22

struct Observation {
  int symbol = 0;
  std::array<double, kNumSources> eta{};
  int rule = 0;  // the rule that gave eta (above)
};

struct LabellerOptions {
  int width = 320, height = 240;  // the frame's size
  double gripper_area = 0.0;      // the gripper's bounding box in pixels (A above)
  double onion_area = 0.0;        // an onion's area in pixels
  double near = 1.2;              // "near": centroids closer than this many gripper-blob diagonals
  double large_onion = 4.0;       // "large": more than this many onion areas
  double dark_share = 0.08;       // Dark above this share of dark pixels
  bool uniform_eta = false;       // the Uniform-eta variant: eta = 1/4 everywhere
};

// The labeller's options for a camera's frames `width` pixels wide (its reference sizes
// from the camera's view; the thresholds at their defaults).
LabellerOptions labeller_options(const CameraView& camera, int width, bool uniform_eta = false);

int gripper_region(double x, double y, int width, int height);

// The observations of one frame's detections, in the detections' order.
std::vector<Observation> label(const std::vector<Detection>& detections, const LabellerOptions& options);

}  // namespace hbirl::perception
