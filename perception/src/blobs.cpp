#include "perception/blobs.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <mutex>
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

namespace {

using ThresholdKey = std::array<double, 18>;

ThresholdKey key_of(const BlobOptions& o) {
  ThresholdKey k{};
  const cv::Scalar* bounds[] = {&o.blue_low, &o.blue_high, &o.onion_low, &o.onion_high, &o.dark_low, &o.dark_high};
  for (size_t i = 0; i < 6; ++i) {
    for (size_t c = 0; c < 3; ++c) k[3 * i + c] = (*bounds[i])[static_cast<int>(c)];
  }
  return k;
}

// The smallest rectangle holding the rows and columns that have the bit.
cv::Rect extent(const std::vector<unsigned char>& rows, const std::vector<unsigned char>& cols, unsigned char bit) {
  const auto has = [bit](unsigned char x) { return (x & bit) != 0; };
  const int top = static_cast<int>(std::find_if(rows.begin(), rows.end(), has) - rows.begin());
  if (top == static_cast<int>(rows.size())) return {};
  const int bottom = static_cast<int>(rows.rend() - std::find_if(rows.rbegin(), rows.rend(), has));
  const int left = static_cast<int>(std::find_if(cols.begin(), cols.end(), has) - cols.begin());
  const int right = static_cast<int>(cols.rend() - std::find_if(cols.rbegin(), cols.rend(), has));
  return {left, top, right - left, bottom - top};
}

}  // namespace

std::shared_ptr<const ColourTable> ColourTable::for_options(const BlobOptions& options) {
  static std::mutex mutex;
  static std::map<ThresholdKey, std::shared_ptr<const ColourTable>> tables;
  const std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<const ColourTable>& table = tables[key_of(options)];
  if (!table) table = std::make_shared<const ColourTable>(options);
  return table;
}

ColourTable::ColourTable(const BlobOptions& options) : bits_(size_t{1} << 24) {
  // Every colour once, as a 4096 x 4096 image: pixel i is (b, g, r) = (i >> 16, i >> 8, i) & 255.
  cv::Mat all(4096, 4096, CV_8UC3);
  unsigned char* p = all.ptr<unsigned char>(0);
  for (size_t i = 0; i < bits_.size(); ++i, p += 3) {
    p[0] = static_cast<unsigned char>(i >> 16);
    p[1] = static_cast<unsigned char>(i >> 8);
    p[2] = static_cast<unsigned char>(i);
  }
  cv::Mat hsv, blue, onion, dark;
  cv::cvtColor(all, hsv, cv::COLOR_BGR2HSV);
  all.release();
  cv::inRange(hsv, options.blue_low, options.blue_high, blue);
  cv::inRange(hsv, options.onion_low, options.onion_high, onion);
  cv::inRange(hsv, options.dark_low, options.dark_high, dark);
  const unsigned char* b = blue.ptr<unsigned char>(0);
  const unsigned char* o = onion.ptr<unsigned char>(0);
  const unsigned char* d = dark.ptr<unsigned char>(0);
  for (size_t i = 0; i < bits_.size(); ++i) {
    bits_[i] = static_cast<unsigned char>((b[i] ? kBlue : 0) | (o[i] || d[i] ? kOnion : 0) | (d[i] ? kDark : 0));
  }
}

void ColourTable::classify(const cv::Mat& bgr, ColourClasses& out) const {
  CV_Assert(bgr.type() == CV_8UC3);
  out.bits.create(bgr.size(), CV_8UC1);
  std::vector<unsigned char> rows(static_cast<size_t>(bgr.rows)), cols(static_cast<size_t>(bgr.cols));
  for (int r = 0; r < bgr.rows; ++r) {
    const unsigned char* p = bgr.ptr<unsigned char>(r);
    unsigned char* __restrict k = out.bits.ptr<unsigned char>(r);
    for (int c = 0; c < bgr.cols; ++c, p += 3) k[c] = classes(p[0], p[1], p[2]);
    unsigned char any = 0;
    for (int c = 0; c < bgr.cols; ++c) {
      any |= k[c];
      cols[static_cast<size_t>(c)] |= k[c];
    }
    rows[static_cast<size_t>(r)] = any;
  }
  out.blue_extent = extent(rows, cols, kBlue);
  out.onion_extent = extent(rows, cols, kOnion);
}

BlobDetector::BlobDetector(BlobOptions options)
    : options_(std::move(options)), table_(ColourTable::for_options(options_)) {}

// Connected components of one colour class, inside its extent only: labelling costs time
// per pixel scanned, and the classes are mostly empty. OpenCV labels; the statistics (area,
// box, centroid, dark pixels) are gathered here in one pass, several times faster than
// connectedComponentsWithStats's own.
void BlobDetector::components(unsigned char bit, const cv::Rect& extent, BlobClass cls, std::vector<Detection>& out) {
  if (extent.empty()) return;
  const cv::Mat bits = classes_.bits(extent);
  cv::Mat mask = mask_(extent), labels = labels_(extent);  // views: no allocation per frame
  cv::bitwise_and(bits, cv::Scalar(bit), mask);
  const int n = cv::connectedComponents(mask, labels, 8, CV_32S);
  stats_.assign(static_cast<size_t>(n), BlobStats{});
  order_.clear();
  for (int r = 0; r < labels.rows; ++r) {
    const int* label = labels.ptr<int>(r);
    const unsigned char* k = bits.ptr<unsigned char>(r);
    for (int c = 0; c < labels.cols; ++c) {
      if (label[c] == 0) continue;
      BlobStats& s = stats_[static_cast<size_t>(label[c])];
      if (s.area == 0) {
        s.left = s.right = c;
        s.top = s.bottom = r;
        order_.push_back(label[c]);
      }
      ++s.area;
      s.dark += (k[c] & ColourTable::kDark) != 0;
      s.sum_x += c;
      s.sum_y += r;
      s.left = std::min(s.left, c);
      s.right = std::max(s.right, c);
      s.bottom = r;
    }
  }
  const int min_area = std::max(4, static_cast<int>(options_.min_area_share * classes_.bits.rows * classes_.bits.cols));
  // Blobs in the raster order of their first pixel, whatever numbering the labelling chose
  // (OpenCV's parallel labelling may number them differently): same frame, same output.
  for (const int i : order_) {
    const BlobStats& s = stats_[static_cast<size_t>(i)];
    if (s.area < min_area) continue;
    Detection d;
    d.cls = cls;
    d.x = s.sum_x / s.area + extent.x;
    d.y = s.sum_y / s.area + extent.y;
    d.area = s.area;
    d.box = cv::Rect(s.left + extent.x, s.top + extent.y, s.right - s.left + 1, s.bottom - s.top + 1);
    if (cls == BlobClass::kOnion) d.dark_share = static_cast<double>(s.dark) / s.area;
    out.push_back(d);
  }
}

std::vector<Detection> BlobDetector::detect(const cv::Mat& bgr) {
  validate_frame(bgr, options_.expected_width, options_.expected_height);
  table_->classify(bgr, classes_);
  mask_.create(bgr.size(), CV_8UC1);
  labels_.create(bgr.size(), CV_32SC1);
  std::vector<Detection> out;
  components(ColourTable::kBlue, classes_.blue_extent, BlobClass::kGripper, out);
  components(ColourTable::kOnion, classes_.onion_extent, BlobClass::kOnion, out);
  return out;
}

}  // namespace hbirl::perception
