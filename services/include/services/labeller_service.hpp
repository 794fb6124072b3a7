#pragma once
// The labeller service (docs/services.md "Services and channels"): the onion camera's detections as the paper's
// observations with their source distributions eta.
#include "hbirl/detections_t.hpp"
#include "hbirl/observations_t.hpp"
#include "perception/camera_view.hpp"
#include "services/bus.hpp"
#include "services/channels.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

// The labeller: DETECTIONS -> OBSERVATIONS with eta (the paper's rules, paper §Experiments B),
// for the frames of the camera `camera` (its domain's, Domain::camera).
class LabellerService {
 public:
  LabellerService(Bus& bus, Counters& counters, const perception::CameraView& camera, bool uniform_eta = false);

 private:
  void on_detections(const hbirl::detections_t& m);
  Bus& bus_;
  Counters& counters_;
  perception::CameraView camera_;
  bool uniform_eta_;
  std::int64_t seq_ = 0;
  SequenceTracker detections_;
  Subscriptions subs_;  // last: ends first
};

}  // namespace hbirl::services
