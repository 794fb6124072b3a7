#include "perception/labeller.hpp"

#include <algorithm>
#include <cmath>

namespace hbirl::perception {

LabellerOptions labeller_options(const CameraView& camera, int width, bool uniform_eta) {
  LabellerOptions o;
  o.width = width;
  o.height = camera.height(width);
  const PixelBox g = camera.gripper_box(width);
  o.gripper_area = static_cast<double>(g.width) * g.height;
  o.onion_area = camera.onion_area(width);
  o.uniform_eta = uniform_eta;
  return o;
}

int gripper_region(double x, double y, int width, int height) {
  const int col = std::clamp(static_cast<int>(x * kRegionColumns / width), 0, kRegionColumns - 1);
  const int row = std::clamp(static_cast<int>(y * kRegionRows / height), 0, kRegionRows - 1);
  return row * kRegionColumns + col;
}

namespace {
double round_to_twentieths(double x) { return std::clamp(std::round(x * 20.0) / 20.0, 0.05, 0.95); }
}  // namespace

std::vector<Observation> label(const std::vector<Detection>& detections, const LabellerOptions& o) {
  std::vector<Observation> out;
  out.reserve(detections.size());
  for (const Detection& d : detections) {
    Observation obs;
    if (d.cls == BlobClass::kGripper) {
      obs.symbol = gripper_region(d.x, d.y, o.width, o.height);
      const double area = std::max(1.0, static_cast<double>(d.area));
      const double r = round_to_twentieths(std::min(area, o.gripper_area) / std::max(area, o.gripper_area));
      obs.eta = {r, 1.0 - r, 0.0, 0.0};
      obs.rule = static_cast<int>(std::lround(r * 20.0)) - 1;
    } else {
      obs.symbol = d.dark_share > o.dark_share ? kDarkOnion : kBrightOnion;
      bool near = false;
      for (const Detection& g : detections) {
        if (g.cls != BlobClass::kGripper) continue;
        const double diagonal = std::hypot(g.box.width, g.box.height);
        if (std::hypot(d.x - g.x, d.y - g.y) < o.near * diagonal) near = true;
      }
      if (near) {
        obs.eta = {0.8, 0.0, 0.1, 0.1};
        obs.rule = kOnionNearGripperRule;
      } else if (d.area > o.large_onion * o.onion_area) {
        obs.eta = {0.1, 0.05, 0.25, 0.6};
        obs.rule = kLargeOnionRule;
      } else {
        obs.eta = {0.1, 0.05, 0.6, 0.25};
        obs.rule = kSmallOnionRule;
      }
    }
    if (o.uniform_eta) obs.eta.fill(1.0 / kNumSources);
    out.push_back(obs);
  }
  return out;
}

}  // namespace hbirl::perception
