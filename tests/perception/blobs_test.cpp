#include "perception/blobs.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "learner/input_error.hpp"
#include "perception/labeller.hpp"

namespace hbirl::perception {
namespace {

const cv::Scalar kGrey(200, 200, 196);
const cv::Scalar kBlue(200, 70, 20);
const cv::Scalar kOnion(40, 160, 215);
const cv::Scalar kSpot(25, 45, 70);

cv::Mat blank() { return cv::Mat(240, 320, CV_8UC3, kGrey); }

// Synthetic frames with known blobs: positions, sizes and dark shares come back.
TEST(BlobDetector, FindsKnownBlobs) {
  cv::Mat frame = blank();
  cv::rectangle(frame, cv::Rect(100, 50, 20, 16), kBlue, cv::FILLED);  // 320 px, centre (109.5, 57.5)
  cv::rectangle(frame, cv::Rect(200, 150, 10, 10), kOnion, cv::FILLED);
  cv::rectangle(frame, cv::Rect(40, 180, 10, 10), kOnion, cv::FILLED);
  cv::rectangle(frame, cv::Rect(40, 180, 10, 4), kSpot, cv::FILLED);  // 40% of this onion is dark
  BlobDetector detector;
  const std::vector<Detection> d = detector.detect(frame);
  ASSERT_EQ(d.size(), 3u);
  EXPECT_EQ(d[0].cls, BlobClass::kGripper);
  EXPECT_EQ(d[0].area, 320);
  EXPECT_NEAR(d[0].x, 109.5, 1e-9);
  EXPECT_NEAR(d[0].y, 57.5, 1e-9);
  int onions = 0;
  for (const auto& x : d) {
    if (x.cls != BlobClass::kOnion) continue;
    ++onions;
    EXPECT_EQ(x.area, 100);
    EXPECT_NEAR(x.dark_share, x.x < 100 ? 0.4 : 0.0, 1e-12);
  }
  EXPECT_EQ(onions, 2);
}

// The colour table gives exactly what OpenCV's cvtColor and inRange give, pixel for pixel,
// on frames of random colours (every class and boundary reachable) and with non-default
// thresholds; the extents are the masks' bounding rectangles.
TEST(ColourTable, SameClassesAsCvtColorAndInRange) {
  BlobOptions options;
  options.onion_low = cv::Scalar(10, 100, 80);  // not the defaults: a second table
  cv::RNG rng(7);
  for (int trial = 0; trial < 3; ++trial) {
    cv::Mat frame(120, 160, CV_8UC3);
    rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
    if (trial == 2) {  // sparse classes: a few blobs on grey, so the extents are tight
      frame.setTo(kGrey);
      cv::rectangle(frame, cv::Rect(30, 20, 12, 9), kBlue, cv::FILLED);
      cv::rectangle(frame, cv::Rect(100, 70, 7, 30), kOnion, cv::FILLED);
      cv::rectangle(frame, cv::Rect(150, 110, 10, 10), kSpot, cv::FILLED);
    }
    ColourClasses classes;
    ColourTable::for_options(options)->classify(frame, classes);
    cv::Mat hsv, blue, onion, dark;
    cv::cvtColor(frame, hsv, cv::COLOR_BGR2HSV);
    cv::inRange(hsv, options.blue_low, options.blue_high, blue);
    cv::inRange(hsv, options.onion_low, options.onion_high, onion);
    cv::inRange(hsv, options.dark_low, options.dark_high, dark);
    cv::bitwise_or(onion, dark, onion);
    const auto bit = [&](unsigned char b) {
      cv::Mat m;
      cv::compare(classes.bits & b, 0, m, cv::CMP_NE);
      return m;
    };
    EXPECT_EQ(cv::countNonZero(bit(ColourTable::kBlue) != blue), 0) << "trial " << trial;
    EXPECT_EQ(cv::countNonZero(bit(ColourTable::kOnion) != onion), 0) << "trial " << trial;
    EXPECT_EQ(cv::countNonZero(bit(ColourTable::kDark) != dark), 0) << "trial " << trial;
    EXPECT_GT(cv::countNonZero(blue), 0);
    EXPECT_GT(cv::countNonZero(dark), 0);
    EXPECT_EQ(classes.blue_extent, cv::boundingRect(blue)) << "trial " << trial;
    EXPECT_EQ(classes.onion_extent, cv::boundingRect(onion)) << "trial " << trial;
  }
  EXPECT_EQ(ColourTable::for_options(options), ColourTable::for_options(options));  // built once
}

// Blobs' statistics against OpenCV's connectedComponentsWithStats on a busy frame: many
// blobs of both classes, touching each other and the frame's edges.
TEST(BlobDetector, StatisticsMatchConnectedComponentsWithStats) {
  cv::Mat frame = blank();
  cv::RNG rng(11);
  for (int i = 0; i < 40; ++i) {
    const cv::Point centre(rng.uniform(-5, 325), rng.uniform(-5, 245));
    const cv::Scalar colour = i % 3 == 0 ? kBlue : i % 3 == 1 ? kOnion : kSpot;
    cv::ellipse(frame, centre, cv::Size(rng.uniform(2, 25), rng.uniform(2, 25)), rng.uniform(0, 180), 0, 360, colour,
                cv::FILLED);
  }
  BlobOptions options;
  BlobDetector detector(options);
  const std::vector<Detection> found = detector.detect(frame);
  cv::Mat hsv, masks[2], dark, labels, stats, centroids;
  cv::cvtColor(frame, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, options.blue_low, options.blue_high, masks[0]);
  cv::inRange(hsv, options.onion_low, options.onion_high, masks[1]);
  cv::inRange(hsv, options.dark_low, options.dark_high, dark);
  cv::bitwise_or(masks[1], dark, masks[1]);
  const int min_area = static_cast<int>(options.min_area_share * 320 * 240);
  size_t expected = 0;
  for (int m = 0; m < 2; ++m) {
    const BlobClass cls = m == 0 ? BlobClass::kGripper : BlobClass::kOnion;
    const int n = cv::connectedComponentsWithStats(masks[m], labels, stats, centroids, 8, CV_32S);
    for (int i = 1; i < n; ++i) {
      const int area = stats.at<int>(i, cv::CC_STAT_AREA);
      if (area < min_area) continue;
      ++expected;
      const cv::Rect box(stats.at<int>(i, cv::CC_STAT_LEFT), stats.at<int>(i, cv::CC_STAT_TOP),
                         stats.at<int>(i, cv::CC_STAT_WIDTH), stats.at<int>(i, cv::CC_STAT_HEIGHT));
      const auto same = [&](const Detection& d) { return d.cls == cls && d.box == box && d.area == area; };
      const auto it = std::find_if(found.begin(), found.end(), same);
      ASSERT_NE(it, found.end()) << "blob " << i << " of class " << m << " at " << box;
      EXPECT_NEAR(it->x, centroids.at<double>(i, 0), 1e-9);
      EXPECT_NEAR(it->y, centroids.at<double>(i, 1), 1e-9);
      if (cls == BlobClass::kOnion) {
        EXPECT_NEAR(it->dark_share, static_cast<double>(cv::countNonZero((labels == i) & dark)) / area, 1e-12);
      }
    }
  }
  EXPECT_EQ(found.size(), expected);
  EXPECT_GT(expected, 10u);
}

// Nothing of the gripper's or an onion's colour: no detections (an occluded step).
TEST(BlobDetector, NoBlobsNoDetections) {
  cv::Mat frame = blank();
  cv::rectangle(frame, cv::Rect(0, 150, 320, 90), cv::Scalar(150, 150, 148), cv::FILLED);  // floor
  cv::circle(frame, cv::Point(160, 100), 30, cv::Scalar(40, 40, 45), cv::FILLED);          // dark hair: not an onion
  BlobDetector detector;
  EXPECT_TRUE(detector.detect(frame).empty());
}

TEST(BlobDetector, TinySpecksAreNoise) {
  cv::Mat frame = blank();
  cv::rectangle(frame, cv::Rect(10, 10, 2, 2), kBlue, cv::FILLED);
  BlobDetector detector;
  EXPECT_TRUE(detector.detect(frame).empty());
}

void expect_rejected(const cv::Mat& frame, const std::string& words, int width = 0, int height = 0) {
  BlobOptions options;
  options.expected_width = width;
  options.expected_height = height;
  BlobDetector detector(options);
  try {
    detector.detect(frame);
    FAIL() << "accepted a bad frame (" << words << ")";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("frame"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

TEST(BlobDetector, RejectsCorruptFrames) {
  expect_rejected(cv::Mat(), "empty");
  expect_rejected(cv::Mat(240, 320, CV_8UC1, cv::Scalar(0)), "1 channel");
  expect_rejected(cv::Mat(240, 320, CV_8UC4, cv::Scalar(0, 0, 0, 0)), "4 channel");
  expect_rejected(cv::Mat(240, 320, CV_32FC3, cv::Scalar(0, 0, 0)), "depth");
  expect_rejected(blank(), "expected 640x480", 640, 480);
}

// Regions: 5 columns x 4 rows of equal size, row-major from the top left.
TEST(Labeller, GripperRegions) {
  EXPECT_EQ(gripper_region(0, 0, 320, 240), 0);
  EXPECT_EQ(gripper_region(319.9, 0, 320, 240), 4);
  EXPECT_EQ(gripper_region(0, 239.9, 320, 240), 15);
  EXPECT_EQ(gripper_region(319.9, 239.9, 320, 240), 19);
  EXPECT_EQ(gripper_region(64.0, 60.0, 320, 240), 6);
  EXPECT_EQ(gripper_region(63.9, 59.9, 320, 240), 0);
}

Detection blob(BlobClass cls, double x, double y, int area, double dark = 0.0) {
  Detection d;
  d.cls = cls;
  d.x = x;
  d.y = y;
  d.area = area;
  const int side = static_cast<int>(std::sqrt(area));
  d.box = cv::Rect(static_cast<int>(x) - side / 2, static_cast<int>(y) - side / 2, side, side);
  d.dark_share = dark;
  return d;
}

// The labeller's rules (paper §Experiments B and appendix; docs/onion-camera.md "The onion camera"), case by case.
TEST(Labeller, EtaRules) {
  LabellerOptions o;
  o.gripper_area = 400.0;
  o.onion_area = 180.0;
  const std::vector<Detection> d = {
      blob(BlobClass::kGripper, 160, 120, 400),      // the gripper's size: subject 0.95
      blob(BlobClass::kGripper, 10, 10, 100),        // a quarter of it: 0.25
      blob(BlobClass::kGripper, 300, 200, 1600),     // four times it: 0.25
      blob(BlobClass::kOnion, 160, 135, 150, 0.3),   // near the gripper, dark
      blob(BlobClass::kOnion, 250, 60, 150),         // far, small: other onions
      blob(BlobClass::kOnion, 60, 200, 5000, 0.01),  // far, large: the foreground person
  };
  const std::vector<Observation> obs = label(d, o);
  ASSERT_EQ(obs.size(), d.size());
  EXPECT_EQ(obs[0].symbol, 12);
  EXPECT_DOUBLE_EQ(obs[0].eta[kSubject], 0.95);
  EXPECT_NEAR(obs[0].eta[kBlueShirtPerson], 0.05, 1e-12);
  EXPECT_DOUBLE_EQ(obs[1].eta[kSubject], 0.25);
  EXPECT_DOUBLE_EQ(obs[1].eta[kBlueShirtPerson], 0.75);
  EXPECT_DOUBLE_EQ(obs[2].eta[kSubject], 0.25);
  EXPECT_EQ(obs[3].symbol, kDarkOnion);
  EXPECT_EQ(obs[3].eta, (std::array<double, 4>{0.8, 0.0, 0.1, 0.1}));
  EXPECT_EQ(obs[4].symbol, kBrightOnion);
  EXPECT_EQ(obs[4].eta, (std::array<double, 4>{0.1, 0.05, 0.6, 0.25}));
  EXPECT_EQ(obs[5].symbol, kBrightOnion);
  EXPECT_EQ(obs[5].eta, (std::array<double, 4>{0.1, 0.05, 0.25, 0.6}));
  for (const auto& x : obs) EXPECT_NEAR(x.eta[0] + x.eta[1] + x.eta[2] + x.eta[3], 1.0, 1e-12);
  o.uniform_eta = true;
  for (const auto& x : label(d, o)) EXPECT_EQ(x.eta, (std::array<double, 4>{0.25, 0.25, 0.25, 0.25}));
}

}  // namespace
}  // namespace hbirl::perception
