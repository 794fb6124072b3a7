#pragma once
// Every channel of the service set, in one place, each with its message type (lcmtypes/);
// who publishes it and who listens are in docs/services.md "Services and channels".
#include <cstdint>
#include <cstdio>
#include <string>

#include "hbirl/camera_frame_t.hpp"
#include "hbirl/detections_t.hpp"
#include "hbirl/em_progress_t.hpp"
#include "hbirl/estimate_t.hpp"
#include "hbirl/episode_marker_t.hpp"
#include "hbirl/estep_request_t.hpp"
#include "hbirl/estep_result_t.hpp"
#include "hbirl/frame_request_t.hpp"
#include "hbirl/ground_truth_t.hpp"
#include "hbirl/mdp_t.hpp"
#include "hbirl/observation_model_t.hpp"
#include "hbirl/observations_t.hpp"
#include "hbirl/posterior_t.hpp"
#include "hbirl/reward_t.hpp"
#include "hbirl/service_status_t.hpp"
#include "hbirl/stop_t.hpp"
#include "hbirl/trajectory_t.hpp"
#include "learner/digest.hpp"

namespace hbirl::services {

// A channel and the one message type it carries. Typed publish and subscribe (typed.hpp)
// take a Channel<T>, so a channel cannot be paired with another type anywhere; the raw
// Bus interface takes `name`.
template <class T>
struct Channel {
  using Message = T;
  std::string name;
};

}  // namespace hbirl::services

namespace hbirl::services::channels {

// The sensor side.
inline const Channel<hbirl::camera_frame_t> kCamera{"CAMERA"};              // one frame (PNG)
inline const Channel<hbirl::episode_marker_t> kEpisode{"EPISODE"};          // episode and step begin/end
inline const Channel<hbirl::ground_truth_t> kGroundTruth{"GROUND_TRUTH"};   // controlled run's prior, ILE
inline const Channel<hbirl::detections_t> kDetections{"DETECTIONS"};        // the blobs of one frame
inline const Channel<hbirl::observations_t> kObservations{"OBSERVATIONS"};  // symbols and eta
// The learning side.
inline const Channel<hbirl::mdp_t> kMdp{"MDP"};                               // the MDP the samplers compute on
inline const Channel<hbirl::estep_request_t> kEStepRequest{"ESTEP_REQUEST"};  // one block of an E-step
inline const Channel<hbirl::estep_result_t> kEStepResult{"ESTEP_RESULT"};     // a block's counts
inline const Channel<hbirl::em_progress_t> kEmProgress{"EM_PROGRESS"};        // one EM iteration
inline const Channel<hbirl::observation_model_t> kObservationModel{"OBSERVATION_MODEL"};  // the learned O
inline const Channel<hbirl::posterior_t> kPosterior{"POSTERIOR"};  // the newest demonstration's marginals
inline const Channel<hbirl::reward_t> kReward{"REWARD"};           // the learned reward
inline const Channel<hbirl::estimate_t> kEstimate{"ESTIMATE"};     // after each demonstration (--anytime)
inline const Channel<hbirl::stop_t> kStop{"STOP"};                 // seen enough: end the run (--stop-at-confidence)
inline const Channel<hbirl::frame_request_t> kFrameRequest{"FRAME_REQUEST"};  // frames asked for again
inline const Channel<hbirl::service_status_t> kStatus{"STATUS"};              // every service's heartbeat

// trajectory_t: the blocks of the data set one sampler worker is given, on a channel of
// its own -- "TRAJECTORY_" and 16 hexadecimal digits of a digest of its id (an LCM channel
// name holds at most 63 characters; ids are any length) -- so no worker decodes or holds
// another's share. Two ids with one tag would each be sent the other's blocks too, and
// ignore them (trajectory_t.worker).
inline const std::string kTrajectoryPrefix = "TRAJECTORY_";
inline Channel<hbirl::trajectory_t> trajectory_channel(const std::string& worker) {
  Fnv1a h;
  h.add(worker.data(), worker.size());
  char tag[17];
  std::snprintf(tag, sizeof tag, "%016llx", static_cast<unsigned long long>(h.value()));
  return {kTrajectoryPrefix + tag};
}

}  // namespace hbirl::services::channels
