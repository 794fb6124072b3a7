#include "perception/overlay.hpp"

#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace hbirl::perception {

void draw_detections(cv::Mat& frame, const std::vector<Detection>& detections,
                     const std::vector<Observation>& observations) {
  const double scale = frame.cols / 640.0;
  for (size_t i = 0; i < detections.size() && i < observations.size(); ++i) {
    const Detection& d = detections[i];
    const Observation& o = observations[i];
    const bool gripper = d.cls == BlobClass::kGripper;
    const cv::Scalar colour =
        gripper ? cv::Scalar(255, 0, 255) : (o.symbol == kDarkOnion ? cv::Scalar(0, 0, 255) : cv::Scalar(0, 200, 0));
    cv::rectangle(frame, d.box, colour, 1);
    char text[32];
    if (gripper) {
      std::snprintf(text, sizeof text, "g%d %.2f", o.symbol, o.eta[kSubject]);
    } else {
      std::snprintf(text, sizeof text, "%s %.2f", o.symbol == kDarkOnion ? "D" : "B", o.eta[kSubject]);
    }
    cv::putText(frame, text, cv::Point(d.box.x, std::max(8, d.box.y - 2)), cv::FONT_HERSHEY_PLAIN,
                std::max(0.6, 1.4 * scale), colour, 1, cv::LINE_AA);
  }
}

}  // namespace hbirl::perception
