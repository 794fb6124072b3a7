// The labeller service (labeller_service.hpp).
#include "services/labeller_service.hpp"

#include "learner/input_error.hpp"
#include "perception/labeller.hpp"

namespace hbirl::services {

LabellerService::LabellerService(Bus& bus, Counters& counters, const perception::CameraView& camera, bool uniform_eta)
    : bus_(bus), counters_(counters), camera_(camera), uniform_eta_(uniform_eta) {
  subs_.add(bus_,
            subscribe(
                bus_, channels::kDetections, counters_,
                [this](const hbirl::detections_t& m, const Message&) { on_detections(m); }, 2000, Refusals::kWatched));
}

void LabellerService::on_detections(const hbirl::detections_t& m) {
  counters_.gaps += detections_.see(m.seq);
  if (m.width < camera_.min_width || m.width > camera_.max_width) {
    throw InputError("detections.width", "must be between " + std::to_string(camera_.min_width) + " and " +
                                             std::to_string(camera_.max_width) + " pixels (the camera's)");
  }
  if (m.height != camera_.height(m.width))
    throw InputError("detections.height", "is not the camera's height for this width (its aspect ratio)");
  // validate(detections_t) has checked every blob (messages.hpp); the camera's own frame
  // size is checked above.
  std::vector<perception::Detection> found(static_cast<size_t>(m.n));
  for (int i = 0; i < m.n; ++i) {
    auto& d = found[static_cast<size_t>(i)];
    const auto k = static_cast<size_t>(i);
    d.cls = m.cls[k] == hbirl::detections_t::CLASS_GRIPPER ? perception::BlobClass::kGripper
                                                           : perception::BlobClass::kOnion;
    d.x = m.x[k];
    d.y = m.y[k];
    d.area = m.area[k];
    d.box = cv::Rect(m.box_x[k], m.box_y[k], m.box_w[k], m.box_h[k]);
    d.dark_share = m.dark_share[k];
  }
  const std::vector<perception::Observation> obs =
      perception::label(found, perception::labeller_options(camera_, m.width, uniform_eta_));
  hbirl::observations_t o{};
  same_frame(m, o);
  o.seq = ++seq_;
  o.num_symbols = perception::kNumSymbols;
  o.num_sources = perception::kNumSources;
  o.n = static_cast<std::int32_t>(obs.size());
  o.num_context = o.n;  // the rule that gave each eta: learned eta is one distribution per rule
  for (const auto& x : obs) {
    o.symbol.push_back(static_cast<std::int16_t>(x.symbol));
    o.eta.emplace_back(x.eta.begin(), x.eta.end());
    o.context.push_back(x.rule);
  }
  publish(bus_, channels::kObservations, o, counters_);
}

}  // namespace hbirl::services
