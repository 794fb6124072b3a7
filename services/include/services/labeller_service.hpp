#pragma once
// The labeller service (README.md "Services and channels"): the onion camera's detections as the paper's
// observations with their source distributions eta.
#include "hbirl/detections_t.hpp"
#include "hbirl/observations_t.hpp"
#include "services/bus.hpp"
#include "services/channels.hpp"
#include "services/typed.hpp"

namespace hbirl::services {

// The labeller: DETECTIONS -> OBSERVATIONS with eta (the paper's rules, paper §Experiments B).
class LabellerService {
 public:
  LabellerService(Bus& bus, Counters& counters, bool uniform_eta = false);

 private:
  void on_detections(const hbirl::detections_t& m);
  Bus& bus_;
  Counters& counters_;
  bool uniform_eta_;
  std::int64_t seq_ = 0;
  SequenceTracker detections_;
  Subscriptions subs_;  // last: ends first
};

}  // namespace hbirl::services
