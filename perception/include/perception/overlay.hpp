#pragma once
// Draws what perception saw on a frame: a box per blob with its symbol and the labeller's
// eta for the subject (for figures and for eyeballing a camera set-up).
#include <vector>

#include "perception/labeller.hpp"

namespace hbirl::perception {

// detections[i] was labelled observations[i].
void draw_detections(cv::Mat& frame, const std::vector<Detection>& detections,
                     const std::vector<Observation>& observations);

}  // namespace hbirl::perception
