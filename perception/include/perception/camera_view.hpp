#pragma once
// What a camera shows of the task, as shares of its frame: the labeller's reference sizes
// (perception/labeller.hpp: the gripper's box A and an onion's area) at any resolution.
// A domain with a camera states it (sim_driver/registry/domain.hpp, Domain::camera); the
// labeller service is configured by it, never by the scene that draws the frames.
#include <cmath>

namespace hbirl::perception {

struct PixelBox {
  int width = 0, height = 0;
};

struct CameraView {
  // The frame's height is width * aspect_numerator / aspect_denominator (whole pixels,
  // rounded down), for widths in [min_width, max_width].
  int aspect_numerator = 3, aspect_denominator = 4;
  int min_width = 160, max_width = 4096;
  double gripper_width = 0.0, gripper_height = 0.0;  // the gripper's box: shares of the width, of the height
  double onion_radius = 0.0;                         // an onion's radius: share of the width

  int height(int width) const { return width * aspect_numerator / aspect_denominator; }
  // The gripper's box in whole pixels, and an onion's area in pixels, at this width.
  PixelBox gripper_box(int width) const {
    return {static_cast<int>(std::lround(gripper_width * width)),
            static_cast<int>(std::lround(gripper_height * height(width)))};
  }
  double onion_area(int width) const {
    constexpr double kPi = 3.14159265358979323846;
    const double r = onion_radius * width;
    return kPi * r * r;
  }
};

}  // namespace hbirl::perception
