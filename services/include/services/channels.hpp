#pragma once
// Every channel of the service set, in one place: the message type of each (lcmtypes/),
// who publishes it and who listens are in README.md "Services and channels".
#include <cstdint>
#include <cstdio>
#include <string>

#include "learner/digest.hpp"

namespace hbirl::services::channels {

// The sensor side.
inline const std::string kCamera = "CAMERA";                      // camera_frame_t: one frame (PNG)
inline const std::string kEpisode = "EPISODE";                    // episode_marker_t: episode and step begin/end
inline const std::string kGroundTruth = "GROUND_TRUTH";           // ground_truth_t: controlled run's prior, ILE
inline const std::string kDetections = "DETECTIONS";              // detections_t: the blobs of one frame
inline const std::string kObservations = "OBSERVATIONS";          // observations_t: symbols and eta
// The learning side.
inline const std::string kMdp = "MDP";                            // mdp_t: the MDP the samplers compute on
inline const std::string kTrajectory = "TRAJECTORY";              // prefix of trajectory_channel()
inline const std::string kEStepRequest = "ESTEP_REQUEST";         // estep_request_t: one block of an E-step
inline const std::string kEStepResult = "ESTEP_RESULT";           // estep_result_t: a block's counts
inline const std::string kEmProgress = "EM_PROGRESS";             // em_progress_t: one EM iteration
inline const std::string kObservationModel = "OBSERVATION_MODEL"; // observation_model_t: the learned O
inline const std::string kPosterior = "POSTERIOR";                // posterior_t: the newest demonstration's marginals
inline const std::string kReward = "REWARD";                      // reward_t: the learned reward
inline const std::string kFrameRequest = "FRAME_REQUEST";         // frame_request_t: frames asked for again
inline const std::string kStatus = "STATUS";                      // service_status_t: every service's heartbeat

// trajectory_t: the blocks of the data set one sampler worker is given, on a channel of
// its own -- "TRAJECTORY_" and 16 hexadecimal digits of a digest of its id (an LCM channel
// name holds at most 63 characters; ids are any length) -- so no worker decodes or holds
// another's share. Two ids with one tag would each be sent the other's blocks too, and
// ignore them (trajectory_t.worker).
inline std::string trajectory_channel(const std::string& worker) {
  Fnv1a h;
  h.add(worker.data(), worker.size());
  char tag[17];
  std::snprintf(tag, sizeof tag, "%016llx", static_cast<unsigned long long>(h.value()));
  return kTrajectory + "_" + tag;
}

}  // namespace hbirl::services::channels
