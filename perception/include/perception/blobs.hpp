#pragma once
// Colour-blob perception (SPEC §3 "Onion sorting"; paper §Experiments B): HSV thresholds
// and connected components (OpenCV's own functions) find the blue blobs (the gripper, or
// anything of its colour) and the onion-coloured blobs in a BGR frame, with each blob's
// position, size and share of dark (blemish-coloured) pixels.
#include <opencv2/core.hpp>
#include <vector>

namespace hbirl::perception {

enum class BlobClass { kGripper, kOnion };

struct Detection {
  BlobClass cls = BlobClass::kGripper;
  double x = 0.0, y = 0.0;   // centroid, pixels
  int area = 0;              // pixels
  cv::Rect box;
  double dark_share = 0.0;   // onions: share of the blob's pixels that are dark
};

struct BlobOptions {
  // HSV ranges, OpenCV's scale (H 0-180, S and V 0-255).
  cv::Scalar blue_low{95, 100, 60}, blue_high{130, 255, 255};
  cv::Scalar onion_low{12, 110, 90}, onion_high{32, 255, 255};
  cv::Scalar dark_low{4, 70, 25}, dark_high{32, 255, 89};  // the blemish: dark, onion-hued
  double min_area_share = 1.2e-4;  // blobs smaller than this share of the frame are noise
  int expected_width = 0;          // 0: any size
  int expected_height = 0;
};

class BlobDetector {
 public:
  explicit BlobDetector(BlobOptions options = {});
  // Throws InputError("frame", ...) for an empty frame, one that is not 8-bit 3-channel,
  // or one of the wrong size (when expected_width/height are set).
  std::vector<Detection> detect(const cv::Mat& bgr);

 private:
  void components(const cv::Mat& mask, BlobClass cls, const cv::Mat* dark, std::vector<Detection>& out);
  BlobOptions options_;
  cv::Mat hsv_, blue_, onion_, dark_, labels_, stats_, centroids_;
  std::vector<int> dark_count_;
};

// Checks a frame's shape; throws InputError naming what is wrong.
void validate_frame(const cv::Mat& frame, int expected_width = 0, int expected_height = 0);

}  // namespace hbirl::perception
