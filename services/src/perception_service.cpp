// The perception service (perception_service.hpp).
#include "services/perception_service.hpp"

#include "learner/input_error.hpp"
#include "perception/image_codec.hpp"
#include "services/frame_header.hpp"

namespace hbirl::services {

PerceptionService::PerceptionService(Bus& bus, Counters& counters) : bus_(bus), counters_(counters) {
  // Frames come at camera rate; a queue of a few seconds' worth rides out a slow moment.
  subs_.add(bus_, subscribe(
                      bus_, channels::kCamera, counters_,
                      [this](const hbirl::camera_frame_t& m, const Message&) { on_frame(m); }, 2000));
}

void PerceptionService::on_frame(const hbirl::camera_frame_t& m) {
  counters_.gaps += frames_.see(m.seq);
  if (m.encoding != "png" && m.encoding != "jpeg")
    throw InputError("camera_frame.encoding", "'" + m.encoding + "' (png or jpeg)");
  if (m.size <= 0) throw InputError("camera_frame.data", "is empty");
  if (m.width < 1 || m.height < 1 || m.width > 4096 || m.height > 4096) {
    throw InputError("camera_frame.width", "the frame must be between 1x1 and 4096x4096");  // before decoding it
  }
  // The image's own header too: it is what the decoder allocates for (frame_header.hpp).
  const auto stated = encoded_frame_size(m.data.data(), m.data.size(), m.encoding);
  if (!stated) throw InputError("camera_frame.data", "does not begin as " + m.encoding + " does");
  if (stated->first != m.width || stated->second != m.height) {
    throw InputError("camera_frame.width", "the image's header says " + std::to_string(stated->first) + "x" +
                                               std::to_string(stated->second) + ", the message says " +
                                               std::to_string(m.width) + "x" + std::to_string(m.height));
  }
  const cv::Mat frame = perception::decode_image(m.data.data(), m.data.size(), 4096, 4096);
  if (frame.empty()) throw InputError("camera_frame.data", "does not decode as " + m.encoding);
  if (frame.cols != m.width || frame.rows != m.height) {
    throw InputError("camera_frame.width", "the image is " + std::to_string(frame.cols) + "x" +
                                               std::to_string(frame.rows) + ", the message says " +
                                               std::to_string(m.width) + "x" + std::to_string(m.height));
  }
  const std::vector<perception::Detection> found = detector_.detect(frame);
  hbirl::detections_t d{};
  same_frame(m, d);
  d.seq = ++seq_;
  d.width = m.width;
  d.height = m.height;
  d.n = static_cast<std::int32_t>(found.size());
  for (const auto& x : found) {
    d.cls.push_back(x.cls == perception::BlobClass::kGripper ? hbirl::detections_t::CLASS_GRIPPER
                                                             : hbirl::detections_t::CLASS_ONION);
    d.x.push_back(static_cast<float>(x.x));
    d.y.push_back(static_cast<float>(x.y));
    d.area.push_back(x.area);
    d.box_x.push_back(static_cast<std::int16_t>(x.box.x));
    d.box_y.push_back(static_cast<std::int16_t>(x.box.y));
    d.box_w.push_back(static_cast<std::int16_t>(x.box.width));
    d.box_h.push_back(static_cast<std::int16_t>(x.box.height));
    d.dark_share.push_back(static_cast<float>(x.dark_share));
  }
  publish(bus_, channels::kDetections, d, counters_);
}

}  // namespace hbirl::services
