#pragma once
// The perception service (docs/services.md "Services and channels"): colour blobs in the onion camera's frames.
#include "hbirl/camera_frame_t.hpp"
#include "hbirl/detections_t.hpp"
#include "perception/blobs.hpp"
#include "services/bus.hpp"
#include "services/channels.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

// Perception: CAMERA -> DETECTIONS, one message per frame (also when it is empty).
class PerceptionService {
 public:
  PerceptionService(Bus& bus, Counters& counters);

 private:
  void on_frame(const hbirl::camera_frame_t& m);
  Bus& bus_;
  Counters& counters_;
  perception::BlobDetector detector_;
  std::int64_t seq_ = 0;
  SequenceTracker frames_;
  Subscriptions subs_;  // last: ends first
};

}  // namespace hbirl::services
