#include "perception/blobs.hpp"

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "learner/input_error.hpp"

namespace hbirl::perception {

void validate_frame(const cv::Mat& frame, int expected_width, int expected_height) {
  if (frame.empty()) throw InputError("frame", "is empty");
  if (frame.depth() != CV_8U || frame.channels() != 3) {
    throw InputError("frame", "expected 8-bit BGR with 3 channels, got " + std::to_string(frame.channels()) +
                                  " channel(s) of depth code " + std::to_string(frame.depth()));
  }
  if ((expected_width > 0 && frame.cols != expected_width) || (expected_height > 0 && frame.rows != expected_height)) {
    throw InputError("frame", "is " + std::to_string(frame.cols) + "x" + std::to_string(frame.rows) + ", expected " +
                                  std::to_string(expected_width) + "x" + std::to_string(expected_height));
  }
}

BlobDetector::BlobDetector(BlobOptions options) : options_(std::move(options)) {}

void BlobDetector::components(const cv::Mat& mask, BlobClass cls, const cv::Mat* dark, std::vector<Detection>& out) {
  const int n = cv::connectedComponentsWithStats(mask, labels_, stats_, centroids_, 8, CV_32S);
  const int min_area = std::max(4, static_cast<int>(options_.min_area_share * mask.rows * mask.cols));
  if (dark) {
    // Dark pixels per component, in one pass over the label image.
    dark_count_.assign(static_cast<size_t>(n), 0);
    for (int r = 0; r < labels_.rows; ++r) {
      const int* label = labels_.ptr<int>(r);
      const unsigned char* d = dark->ptr<unsigned char>(r);
      for (int c = 0; c < labels_.cols; ++c) {
        if (label[c] > 0 && d[c]) ++dark_count_[static_cast<size_t>(label[c])];
      }
    }
  }
  for (int i = 1; i < n; ++i) {
    const int area = stats_.at<int>(i, cv::CC_STAT_AREA);
    if (area < min_area) continue;
    Detection d;
    d.cls = cls;
    d.x = centroids_.at<double>(i, 0);
    d.y = centroids_.at<double>(i, 1);
    d.area = area;
    d.box = cv::Rect(stats_.at<int>(i, cv::CC_STAT_LEFT), stats_.at<int>(i, cv::CC_STAT_TOP), stats_.at<int>(i, cv::CC_STAT_WIDTH),
                     stats_.at<int>(i, cv::CC_STAT_HEIGHT));
    if (dark) d.dark_share = static_cast<double>(dark_count_[static_cast<size_t>(i)]) / area;
    out.push_back(d);
  }
}

std::vector<Detection> BlobDetector::detect(const cv::Mat& bgr) {
  validate_frame(bgr, options_.expected_width, options_.expected_height);
  cv::cvtColor(bgr, hsv_, cv::COLOR_BGR2HSV);
  cv::inRange(hsv_, options_.blue_low, options_.blue_high, blue_);
  cv::inRange(hsv_, options_.onion_low, options_.onion_high, onion_);
  cv::inRange(hsv_, options_.dark_low, options_.dark_high, dark_);
  // An onion is its bright skin and its dark blemish together.
  cv::bitwise_or(onion_, dark_, onion_);
  std::vector<Detection> out;
  components(blue_, BlobClass::kGripper, nullptr, out);
  components(onion_, BlobClass::kOnion, &dark_, out);
  return out;
}

}  // namespace hbirl::perception
