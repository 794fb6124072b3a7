// The perception service (perception_service.hpp).
#include "services/perception_service.hpp"

#include "learner/input_error.hpp"
#include "perception/image_codec.hpp"
#include "services/messages.hpp"

namespace hbirl::services {

PerceptionService::PerceptionService(Bus& bus, Counters& counters) : bus_(bus), counters_(counters) {
  // Frames come at camera rate; a queue of a few seconds' worth rides out a slow moment.
  subs_.add(bus_,
            subscribe(
                bus_, channels::kCamera, counters_,
                [this](const hbirl::camera_frame_t& m, const Message&) { on_frame(m); }, 2000, Refusals::kWatched));
}

void PerceptionService::on_frame(const hbirl::camera_frame_t& m) {
  counters_.gaps += frames_.see(m.seq);
  // validate(camera_frame_t) has checked the message and its image's header (messages.hpp):
  // the decoder allocates only what that states.
  const cv::Mat frame =
      perception::decode_image(m.data.data(), static_cast<size_t>(m.size), kMaxFrameSide, kMaxFrameSide);
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
