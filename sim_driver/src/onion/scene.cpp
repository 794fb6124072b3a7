#include "sim_driver/onion/scene.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <opencv2/imgproc.hpp>

#include "learner/input_error.hpp"
#include "learner/rng.hpp"
#include "sim_driver/onion/onion.hpp"

namespace hbirl::onion {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Colours (BGR). The gripper and the walking person's shirt share a blue; the onions and
// the foreground person's shirt share a golden yellow; nothing else is saturated in those
// hues, so colour-blob perception finds exactly these.
const cv::Scalar kBlue(200, 70, 20);
const cv::Scalar kShirtBlue(190, 66, 24);
const cv::Scalar kOnion(40, 160, 215);
const cv::Scalar kSpot(25, 45, 70);
const cv::Scalar kMustard(30, 150, 200);
const cv::Scalar kWall(200, 200, 196);
const cv::Scalar kFloor(150, 150, 148);
const cv::Scalar kBelt(62, 62, 62);
const cv::Scalar kBin(96, 112, 96);
const cv::Scalar kArm(125, 122, 120);
const cv::Scalar kSkin(150, 172, 205);
const cv::Scalar kHair(40, 40, 45);
const cv::Scalar kTrousers(70, 60, 55);
const cv::Scalar kMirror(214, 206, 198);

// Where things are (fractions of width / height).
constexpr double kGripperX[3] = {0.24, 0.50, 0.82};  // at the conveyor, inspection, bin
constexpr double kGripperY[3] = {0.70, 0.45, 0.60};
constexpr double kHoldBelow = 0.055;  // a gripped onion's centre below the gripper's
constexpr double kBeltTop = 0.80, kBeltBottom = 0.90, kBeltEnd = 0.58;
constexpr double kBinLeft = 0.70, kBinRight = 0.92, kBinTop = 0.70, kBinBottom = 0.95;
constexpr double kMirrorLeft = 0.32, kMirrorRight = 0.68, kMirrorTop = 0.03, kMirrorBottom = 0.27;
constexpr double kMirrorScale = 0.42;
constexpr double kOnionRadius = 0.024;  // of the width
constexpr double kGripperW = 0.07, kGripperH = 0.065;
constexpr double kOtherOnionGap = 2.5;  // seconds between other onions on the belt
constexpr double kBeltSpeed = 0.05;     // width per second

double smoothstep(double u) { return u * u * (3.0 - 2.0 * u); }

// A hash of (seed, i) in [0, 1): per-object randomness that does not depend on draw order.
double hash01(std::uint64_t seed, std::uint64_t i) {
  Rng rng(seed, 0x6f6e696f6eULL + i);
  return rng.uniform();
}

}  // namespace

SceneConfig SceneConfig::controlled() {
  SceneConfig c;
  c.blue_shirt_person = c.other_onions = c.foreground_person = c.mirror = false;
  return c;
}

SceneConfig SceneConfig::parse(const std::string& elements, const std::string& field) {
  SceneConfig c = controlled();
  std::stringstream in(elements);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item == "controlled") continue;
    if (item == "all") {
      c.blue_shirt_person = c.other_onions = c.foreground_person = c.mirror = true;
    } else if (item == "blue-shirt") {
      c.blue_shirt_person = true;
    } else if (item == "other-onions") {
      c.other_onions = true;
    } else if (item == "foreground") {
      c.foreground_person = true;
    } else if (item == "mirror") {
      c.mirror = true;
    } else {
      throw InputError(field,
                       "unknown element '" + item +
                           "' (expected controlled, all, or a list of blue-shirt, other-onions, foreground, mirror)");
    }
  }
  return c;
}

std::string SceneConfig::elements() const {
  if (blue_shirt_person && other_onions && foreground_person && mirror) return "all";
  std::string out;
  const auto add = [&out](bool on, const char* name) {
    if (on) out += (out.empty() ? "" : ",") + std::string(name);
  };
  add(blue_shirt_person, "blue-shirt");
  add(other_onions, "other-onions");
  add(foreground_person, "foreground");
  add(mirror, "mirror");
  return out.empty() ? "controlled" : out;
}

int SceneConfig::height() const { return camera_view().height(width); }

int SceneConfig::frames_per_step() const { return std::max(1, static_cast<int>(std::lround(fps * step_seconds))); }

void SceneConfig::validate() const {
  const perception::CameraView view = camera_view();
  if (width < view.min_width || width > view.max_width) {
    throw InputError("width", "must be between " + std::to_string(view.min_width) + " and " +
                                  std::to_string(view.max_width) + " pixels");
  }
  if (fps < 1 || fps > 240) throw InputError("fps", "must be between 1 and 240");
  if (!(step_seconds > 0.0 && step_seconds <= 60.0)) throw InputError("step_seconds", "must be in (0, 60]");
  if (!(foreground_share >= 0.0 && foreground_share <= 0.95))
    throw InputError("foreground_share", "must be in [0, 0.95]");
}

perception::CameraView camera_view() {
  perception::CameraView v;  // the frame is 4:3 (SceneConfig::height)
  v.min_width = 160;
  v.max_width = 4096;  // as SceneConfig::validate
  v.gripper_width = kGripperW;
  v.gripper_height = kGripperH;
  v.onion_radius = kOnionRadius;
  return v;
}

GripperSize gripper_size(const SceneConfig& config) { return camera_view().gripper_box(config.width); }

double onion_area(const SceneConfig& config) { return camera_view().onion_area(config.width); }

Episode make_episode(const Trajectory& steps, bool blemished, double start_time, std::uint64_t seed) {
  Rng rng(seed);
  Episode e;
  e.steps = steps;
  e.blemished = blemished;
  e.onion_angle = rng.uniform(0.0, 2.0 * kPi);
  e.spot_angle = rng.uniform(0.0, 2.0 * kPi);
  e.start_time = start_time;
  return e;
}

OnionScene::OnionScene(const SceneConfig& config, std::uint64_t seed) : config_(config), seed_(seed) {
  config_.validate();
  Rng rng(seed, 1);
  walk_period_ = rng.uniform(10.0, 16.0);
  walk_phase_ = rng.uniform(0.0, walk_period_);
  occlusion_period_ = rng.uniform(16.0, 24.0);
  occlusion_phase_ = rng.uniform(0.0, occlusion_period_);
  // In front for stay + one walk (half of each) of every period.
  if (config_.foreground_share > 0.0)
    occlusion_stay_ = std::max(0.0, config_.foreground_share * occlusion_period_ - kOcclusionWalk);
  background_ = cv::Mat(config_.height(), config_.width, CV_8UC3);
  draw_background(background_);
}

double OnionScene::time_of(const Episode& episode, int t, int frame) const {
  return episode.start_time + t * config_.step_seconds + (frame + 0.5) / config_.fps;
}

void OnionScene::draw_background(cv::Mat& img) const {
  const int W = img.cols, H = img.rows;
  img.setTo(kWall);
  cv::rectangle(img, cv::Point(0, static_cast<int>(0.62 * H)), cv::Point(W, H), kFloor, cv::FILLED);
  // The conveyor belt with its rollers.
  cv::rectangle(img, cv::Point(0, static_cast<int>(kBeltTop * H)),
                cv::Point(static_cast<int>(kBeltEnd * W), static_cast<int>(kBeltBottom * H)), kBelt, cv::FILLED);
  for (double x = 0.03; x < kBeltEnd; x += 0.06) {
    cv::circle(img, cv::Point(static_cast<int>(x * W), static_cast<int>(kBeltBottom * H)), std::max(2, W / 110),
               cv::Scalar(90, 90, 90), cv::FILLED);
  }
  // The inspection stand.
  cv::line(img, cv::Point(static_cast<int>(0.5 * W), static_cast<int>(0.55 * H)),
           cv::Point(static_cast<int>(0.5 * W), static_cast<int>(0.62 * H)), kArm, std::max(1, W / 160));
  if (config_.mirror) {
    cv::rectangle(img, cv::Point(static_cast<int>(kMirrorLeft * W) - 3, static_cast<int>(kMirrorTop * H) - 3),
                  cv::Point(static_cast<int>(kMirrorRight * W) + 3, static_cast<int>(kMirrorBottom * H) + 3),
                  cv::Scalar(110, 100, 95), cv::FILLED);
  }
}

OnionScene::Pose OnionScene::pose(const Episode& e, int t, double u) const {
  const State s = state(e.steps[static_cast<size_t>(t)].state);
  const int a = e.steps[static_cast<size_t>(t)].action;
  const State n = next_state(s, a, e.blemished ? kBlemished : kGood);
  Pose p{};
  const double m = smoothstep(u);
  p.gx = kGripperX[s.gripper] + (kGripperX[n.gripper] - kGripperX[s.gripper]) * m;
  p.gy = kGripperY[s.gripper] + (kGripperY[n.gripper] - kGripperY[s.gripper]) * m;
  // Gripping and releasing: the gripper dips towards the belt or into the bin and back.
  const bool dips = (a == kGrip && s.onion == kOnConveyor && s.gripper == kAtConveyor) ||
                    (a == kRelease && s.onion == kGripped && s.gripper != kAtInspection);
  if (dips) p.gy += 0.06 * std::sin(kPi * u);
  const double belt_y = kBeltTop - kOnionRadius * config_.width / config_.height();
  const bool held =
      s.onion == kGripped ? !(a == kRelease && n.onion != kGripped && u > 0.5) : (n.onion == kGripped && u > 0.5);
  p.onion_visible = true;
  p.onion_in_bin = false;
  if (held) {
    p.ox = p.gx;
    p.oy = p.gy + kHoldBelow;
  } else if (s.onion == kInBin || n.onion == kInBin) {
    p.ox = kGripperX[kAtBin];
    const double fall = s.onion == kInBin ? 1.0 : std::min(1.0, (u - 0.5) * 2.0);
    p.oy = kGripperY[kAtBin] + kHoldBelow + 0.2 * fall;
    p.onion_in_bin = true;
  } else {
    p.ox = kGripperX[kAtConveyor];
    p.oy = belt_y;
  }
  // The onion turns fully while inspected and swings while carried.
  p.onion_angle = e.onion_angle;
  if (a == kInspect && s.gripper == kAtInspection && s.onion == kGripped) p.onion_angle += 2.0 * kPi * u;
  if (held && a != kInspect) p.onion_angle += 1.3 * std::sin(2.0 * kPi * u + t);
  return p;
}

void OnionScene::draw_onion(cv::Mat& img, double x, double y, double radius, double angle, double spot,
                            bool blemished) const {
  const int W = img.cols, H = img.rows;
  const cv::Point c(static_cast<int>(x * W), static_cast<int>(y * H));
  const int r = std::max(2, static_cast<int>(std::lround(radius * W)));
  cv::circle(img, c, r, kOnion, cv::FILLED, cv::LINE_AA);
  // The blemish faces the viewer when the onion's turn brings it to the front.
  const double facing = std::cos(angle - spot);
  if (blemished && facing > 0.2) {
    const int dx = static_cast<int>(std::lround(0.45 * r * std::sin(angle - spot)));
    cv::circle(img, c + cv::Point(dx, 0), std::max(1, static_cast<int>(std::lround(0.55 * r * facing))), kSpot,
               cv::FILLED, cv::LINE_AA);
  }
}

void OnionScene::draw_mirror(cv::Mat& img, const Pose& p, const Episode& e) const {
  const int W = img.cols, H = img.rows;
  const cv::Rect inside(static_cast<int>(kMirrorLeft * W), static_cast<int>(kMirrorTop * H),
                        static_cast<int>((kMirrorRight - kMirrorLeft) * W),
                        static_cast<int>((kMirrorBottom - kMirrorTop) * H));
  cv::Mat clip = img(inside);
  clip.setTo(kMirror);
  // The reflection: the scene seen from behind, further away (smaller, drawn towards
  // the mirror's centre); the onion shows its far side.
  auto mx = [&](double x) { return 0.5 + (x - 0.5) * kMirrorScale; };
  auto my = [&](double y) { return 0.15 + (y - 0.55) * kMirrorScale; };
  const int gw = std::max(2, static_cast<int>(kGripperW * kMirrorScale * W / 2));
  const int gh = std::max(2, static_cast<int>(kGripperH * kMirrorScale * H / 2));
  const cv::Point g(static_cast<int>(mx(p.gx) * W), static_cast<int>(my(p.gy) * H));
  const cv::Point offset(inside.x, inside.y);
  cv::rectangle(clip, g - offset - cv::Point(gw, gh), g - offset + cv::Point(gw, gh), kBlue, cv::FILLED);
  if (p.onion_visible && !p.onion_in_bin) {
    const cv::Point o(static_cast<int>(mx(p.ox) * W), static_cast<int>(my(p.oy) * H));
    const int r = std::max(2, static_cast<int>(std::lround(kOnionRadius * kMirrorScale * W)));
    cv::circle(clip, o - offset, r, kOnion, cv::FILLED, cv::LINE_AA);
    const double facing = std::cos(p.onion_angle + kPi - e.spot_angle);
    if (e.blemished && facing > 0.2) {
      cv::circle(clip, o - offset, std::max(1, static_cast<int>(std::lround(0.6 * r * facing))), kSpot, cv::FILLED,
                 cv::LINE_AA);
    }
  }
}

void OnionScene::draw_blue_person(cv::Mat& img, double time) const {
  const int W = img.cols, H = img.rows;
  // Walks back and forth behind the expert, across the whole view and a little beyond.
  const double phase = std::fmod(time + walk_phase_, walk_period_) / walk_period_;
  const double tri = phase < 0.5 ? 2.0 * phase : 2.0 - 2.0 * phase;
  const double x = -0.12 + 1.24 * tri;
  const double step = std::sin(2.0 * kPi * time * 1.6);
  auto P = [&](double fx, double fy) { return cv::Point(static_cast<int>(fx * W), static_cast<int>(fy * H)); };
  cv::line(img, P(x - 0.02, 0.52), P(x - 0.03 + 0.02 * step, 0.76), kTrousers, std::max(2, W / 50));
  cv::line(img, P(x + 0.02, 0.52), P(x + 0.03 - 0.02 * step, 0.76), kTrousers, std::max(2, W / 50));
  cv::rectangle(img, P(x - 0.055, 0.27), P(x + 0.055, 0.53), kShirtBlue, cv::FILLED);
  // The tote they carry at their side: the gripper's blue and about its size, at the
  // height of the gripper's working positions -- a false gripper the labeller's size
  // rule cannot tell apart.
  const double side = phase < 0.5 ? 1.0 : -1.0;  // in the hand towards which they walk
  cv::line(img, P(x + side * 0.05, 0.36), P(x + side * 0.1, 0.55), kSkin, std::max(2, W / 90));
  cv::rectangle(img, P(x + side * 0.1 - kGripperW / 2, 0.55), P(x + side * 0.1 + kGripperW / 2, 0.55 + kGripperH),
                kShirtBlue, cv::FILLED);
  cv::circle(img, P(x, 0.22), static_cast<int>(0.033 * W), kSkin, cv::FILLED, cv::LINE_AA);
  cv::ellipse(img, P(x, 0.20), cv::Size(static_cast<int>(0.034 * W), static_cast<int>(0.02 * W)), 0, 180, 360, kHair,
              cv::FILLED);
}

void OnionScene::draw_other_onions(cv::Mat& img, double time) const {
  // Onion k enters the belt at about k * gap seconds and rides it to the end.
  const double travel = (kBeltEnd + 0.05) / kBeltSpeed;
  const long first = static_cast<long>(std::floor((time - travel) / kOtherOnionGap)) - 1;
  const long last = static_cast<long>(std::floor(time / kOtherOnionGap)) + 1;
  const double y = kBeltTop - kOnionRadius * config_.width / config_.height();
  for (long k = std::max(0L, first); k <= last; ++k) {
    const auto id = static_cast<std::uint64_t>(k);
    const double enter = static_cast<double>(k) * kOtherOnionGap + 1.5 * hash01(seed_, 3 * id);
    const double x = -0.05 + kBeltSpeed * (time - enter);
    if (time < enter || x > kBeltEnd) continue;
    const bool blemished = hash01(seed_, 3 * id + 1) < 0.5;
    const double angle = 2.0 * kPi * hash01(seed_, 3 * id + 2) + 0.8 * (time - enter);  // rolling
    draw_onion(img, x, y, kOnionRadius * 0.9, angle, 0.0, blemished);
  }
}

void OnionScene::draw_expert(cv::Mat& img, const Pose& p, const Episode& e) const {
  const int W = img.cols, H = img.rows;
  auto P = [&](double fx, double fy) { return cv::Point(static_cast<int>(fx * W), static_cast<int>(fy * H)); };
  if (p.onion_visible && p.onion_in_bin)
    draw_onion(img, p.ox, p.oy, kOnionRadius, p.onion_angle, e.spot_angle, e.blemished);
  // The bin's front hides an onion that fell in.
  cv::rectangle(img, P(kBinLeft, kBinTop), P(kBinRight, kBinBottom), kBin, cv::FILLED);
  cv::rectangle(img, P(kBinLeft, kBinTop), P(kBinRight, kBinTop + 0.02), cv::Scalar(70, 84, 70), cv::FILLED);
  // The arm: from its base behind the stand to the gripper.
  cv::line(img, P(0.58, 0.98), P(0.62, 0.30), kArm, std::max(3, W / 40));
  cv::line(img, P(0.62, 0.30), P(p.gx, p.gy - kGripperH / 2), kArm, std::max(2, W / 55));
  if (p.onion_visible && !p.onion_in_bin)
    draw_onion(img, p.ox, p.oy, kOnionRadius, p.onion_angle, e.spot_angle, e.blemished);
  const GripperSize g = gripper_size(config_);
  const cv::Point c = P(p.gx, p.gy);
  cv::rectangle(img, c - cv::Point(g.width / 2, g.height / 2),
                c + cv::Point(g.width - g.width / 2, g.height / 2 - g.height / 5), kBlue, cv::FILLED);
  // Two fingers.
  cv::rectangle(img, c + cv::Point(-g.width / 2, g.height / 2 - g.height / 5),
                c + cv::Point(-g.width / 4, g.height / 2), kBlue, cv::FILLED);
  cv::rectangle(img, c + cv::Point(g.width / 4, g.height / 2 - g.height / 5), c + cv::Point(g.width / 2, g.height / 2),
                kBlue, cv::FILLED);
}

void OnionScene::draw_foreground_person(cv::Mat& img, double time) const {
  const int W = img.cols, H = img.rows;
  // Walks in from the left, stands in front of the expert, walks out to the right.
  const double phase = std::fmod(time + occlusion_phase_, occlusion_period_);
  const double kWalk = kOcclusionWalk, kStay = occlusion_stay_;
  double x;
  if (phase < kWalk) {
    x = -0.25 + (0.45 + 0.25) * phase / kWalk;
  } else if (phase < kWalk + kStay) {
    x = 0.45 + 0.02 * std::sin(phase);
  } else if (phase < 2 * kWalk + kStay) {
    x = 0.45 + (1.25 - 0.45) * (phase - kWalk - kStay) / kWalk;
  } else {
    return;  // out of view
  }
  auto P = [&](double fx, double fy) { return cv::Point(static_cast<int>(fx * W), static_cast<int>(fy * H)); };
  cv::rectangle(img, P(x - 0.17, 0.44), P(x + 0.17, 1.0), kMustard, cv::FILLED);
  cv::circle(img, P(x, 0.36), static_cast<int>(0.075 * W), kSkin, cv::FILLED, cv::LINE_AA);
  cv::ellipse(img, P(x, 0.33), cv::Size(static_cast<int>(0.077 * W), static_cast<int>(0.05 * W)), 0, 180, 360, kHair,
              cv::FILLED);
}

void OnionScene::render(const Episode& episode, int t, int frame, cv::Mat& out) const {
  if (t < 0 || t >= static_cast<int>(episode.steps.size())) throw InputError("step", "outside the episode");
  background_.copyTo(out);
  const double time = time_of(episode, t, frame);
  const double u = (frame + 0.5) / config_.frames_per_step();
  const Pose p = pose(episode, t, u);
  if (config_.mirror) draw_mirror(out, p, episode);
  if (config_.blue_shirt_person) draw_blue_person(out, time);
  if (config_.other_onions) draw_other_onions(out, time);
  draw_expert(out, p, episode);
  if (config_.foreground_person) draw_foreground_person(out, time);
}

perception::LabellerOptions labeller_options(const SceneConfig& config, bool uniform_eta) {
  return perception::labeller_options(camera_view(), config.width, uniform_eta);
}

std::vector<Episode> plan_sorts(const Mdp& mdp, const SceneConfig& config, const DemonstrationOptions& options,
                                std::uint64_t seed) {
  const Eigen::VectorXd weights = expert_weights();
  Rng rng(seed, 11);
  std::vector<Episode> sorts;
  double time = options.start_time;
  const bool first_blemished = rng.uniform() < 0.5;
  for (int i = 0; i < options.sorts; ++i) {
    const bool blemished =
        options.alternate_quality ? first_blemished != (i % 2 == 1) : rng.uniform() < options.blemished;
    const Trajectory steps = expert_sort(mdp, weights, rng.uniform_int(3), blemished);
    sorts.push_back(make_episode(steps, blemished, time, rng.next_u64()));
    time += static_cast<double>(steps.size()) * config.step_seconds;
  }
  return sorts;
}

}  // namespace hbirl::onion
