#pragma once
// Colour-blob perception (paper §Experiments B; docs/onion-camera.md "The onion camera"): HSV thresholds
// and connected components (OpenCV's own functions, the thresholds through a colour
// table built with them) find the blue blobs (the gripper, or
// anything of its colour) and the onion-coloured blobs in a BGR frame, with each blob's
// position, size and share of dark (blemish-coloured) pixels.
#include <opencv2/core.hpp>
#include <memory>
#include <vector>

namespace hbirl::perception {

enum class BlobClass { kGripper, kOnion };

struct Detection {
  BlobClass cls = BlobClass::kGripper;
  double x = 0.0, y = 0.0;  // centroid, pixels
  int area = 0;             // pixels
  cv::Rect box;
  double dark_share = 0.0;  // onions: share of the blob's pixels that are dark
};

struct BlobOptions {
  // HSV ranges, OpenCV's scale (H 0-180, S and V 0-255).
  cv::Scalar blue_low{95, 100, 60}, blue_high{130, 255, 255};
  cv::Scalar onion_low{12, 110, 90}, onion_high{32, 255, 255};
  cv::Scalar dark_low{4, 70, 25}, dark_high{32, 255, 89};  // the blemish: dark, onion-hued
  double min_area_share = 1.2e-4;                          // blobs smaller than this share of the frame are noise
  int expected_width = 0;                                  // 0: any size
  int expected_height = 0;
};

// Each pixel's colour classes as bits (ColourTable::kBlue, kOnion, kDark), and the
// smallest rectangles holding the blue and the onion pixels (empty when there are none).
struct ColourClasses {
  cv::Mat bits;  // CV_8UC1, the frame's size
  cv::Rect blue_extent, onion_extent;
};

// The HSV thresholds of BlobOptions applied to every one of the 2^24 BGR colours once, with
// OpenCV's cvtColor(BGR2HSV) and inRange, and kept as a 16 MB table: classifying a frame
// is then one lookup per pixel instead of a colour conversion and three thresholds, and
// gives exactly the same masks (tested). Tables are shared between detectors with the
// same thresholds and kept for the life of the process; the first one for a set of
// thresholds takes a few tenths of a second to build.
class ColourTable {
 public:
  static constexpr unsigned char kBlue = 1, kOnion = 2, kDark = 4;  // an onion is skin or blemish: kOnion covers kDark

  static std::shared_ptr<const ColourTable> for_options(const BlobOptions& options);
  explicit ColourTable(const BlobOptions& options);

  unsigned char classes(unsigned char b, unsigned char g, unsigned char r) const {
    return bits_[(static_cast<size_t>(b) << 16) | (static_cast<size_t>(g) << 8) | r];
  }
  // Classifies an 8-bit BGR frame.
  void classify(const cv::Mat& bgr, ColourClasses& out) const;

 private:
  std::vector<unsigned char> bits_;
};

class BlobDetector {
 public:
  explicit BlobDetector(BlobOptions options = {});
  // Throws InputError("frame", ...) for an empty frame, one that is not 8-bit 3-channel,
  // or one of the wrong size (when expected_width/height are set).
  std::vector<Detection> detect(const cv::Mat& bgr);

 private:
  struct BlobStats {
    int area = 0, dark = 0, left = 0, top = 0, right = 0, bottom = 0;
    double sum_x = 0.0, sum_y = 0.0;
  };
  void components(unsigned char bit, const cv::Rect& extent, BlobClass cls, std::vector<Detection>& out);
  BlobOptions options_;
  std::shared_ptr<const ColourTable> table_;
  ColourClasses classes_;
  cv::Mat mask_, labels_;  // frame-sized; the labelling works in views of them
  std::vector<BlobStats> stats_;
  std::vector<int> order_;
};

// Checks a frame's shape; throws InputError naming what is wrong.
void validate_frame(const cv::Mat& frame, int expected_width = 0, int expected_height = 0);

}  // namespace hbirl::perception
