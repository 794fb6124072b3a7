#include "services/messages.hpp"

#include <cmath>
#include <string>
#include <vector>

#include "learner/input_error.hpp"
#include "learner/observations.hpp"
#include "services/frame_header.hpp"

namespace hbirl::services {

void validate(const hbirl::observations_t& m) {
  if (m.num_symbols < 1) throw InputError("observations.num_symbols", "must be at least 1");
  if (m.num_sources < 1) throw InputError("observations.num_sources", "must be at least 1");
  if (m.episode < 0 || m.episode >= kMaxEpisodes) throw InputError("observations.episode", "out of range");
  if (m.step < 0 || m.frame < 0 || m.step >= kMaxSteps || m.frame >= kMaxFramesPerStep) {
    throw InputError("observations.step", "step or frame out of range");
  }
  if (m.num_context != 0 && m.num_context != m.n) throw InputError("observations.num_context", "must be 0 or n");
  for (int i = 0; i < m.num_context; ++i) {
    const int c = m.context[static_cast<size_t>(i)];
    if (c < 0 || c >= kMaxContexts) {
      throw InputError("observations.context[" + std::to_string(i) + "]",
                       "is outside [0, " + std::to_string(kMaxContexts - 1) + "]");
    }
  }
  for (int i = 0; i < m.n; ++i) {
    const int s = m.symbol[static_cast<size_t>(i)];
    if (s < 0 || s >= m.num_symbols)
      throw InputError("observations.symbol[" + std::to_string(i) + "]", "is outside the alphabet");
    std::vector<double> eta = m.eta[static_cast<size_t>(i)];
    const std::string wrong = normalise_eta(eta.data(), m.num_sources);
    if (!wrong.empty()) throw InputError("observations.eta[" + std::to_string(i) + "]", wrong);
  }
}

void validate(const hbirl::camera_frame_t& m) {
  if (m.episode < 0 || m.episode >= kMaxEpisodes) throw InputError("camera_frame.episode", "out of range");
  if (m.step < 0 || m.frame < 0 || m.step >= kMaxSteps || m.frame >= kMaxFramesPerStep) {
    throw InputError("camera_frame.step", "step or frame out of range");
  }
  if (m.encoding != "png" && m.encoding != "jpeg")
    throw InputError("camera_frame.encoding", "'" + m.encoding + "' (png or jpeg)");
  if (m.size <= 0 || m.size > static_cast<std::int64_t>(m.data.size()))
    throw InputError("camera_frame.size", "does not match its data");
  if (m.width < 1 || m.height < 1 || m.width > kMaxFrameSide || m.height > kMaxFrameSide) {
    throw InputError("camera_frame.width", "the frame must be between 1x1 and " + std::to_string(kMaxFrameSide) + "x" +
                                               std::to_string(kMaxFrameSide));
  }
  const auto stated = encoded_frame_size(m.data.data(), static_cast<size_t>(m.size), m.encoding);
  if (!stated) throw InputError("camera_frame.data", "does not begin as " + m.encoding + " does");
  if (stated->first != m.width || stated->second != m.height) {
    throw InputError("camera_frame.width", "the image's header says " + std::to_string(stated->first) + "x" +
                                               std::to_string(stated->second) + ", the message says " +
                                               std::to_string(m.width) + "x" + std::to_string(m.height));
  }
}

void validate(const hbirl::detections_t& m) {
  if (m.episode < 0 || m.episode >= kMaxEpisodes) throw InputError("detections.episode", "out of range");
  if (m.step < 0 || m.frame < 0 || m.step >= kMaxSteps || m.frame >= kMaxFramesPerStep) {
    throw InputError("detections.step", "step or frame out of range");
  }
  if (m.n < 0) throw InputError("detections.n", "is negative");
  if (m.width < 1 || m.height < 1 || m.width > kMaxFrameSide || m.height > kMaxFrameSide) {
    throw InputError("detections.width", "the frame must be between 1x1 and " + std::to_string(kMaxFrameSide) + "x" +
                                             std::to_string(kMaxFrameSide));
  }
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<size_t>(i);
    if (m.cls[k] != hbirl::detections_t::CLASS_GRIPPER && m.cls[k] != hbirl::detections_t::CLASS_ONION) {
      throw InputError("detections.cls[" + std::to_string(i) + "]", "is not a blob class");
    }
    if (!(m.x[k] >= 0.0f && m.x[k] < m.width) || !(m.y[k] >= 0.0f && m.y[k] < m.height) || m.area[k] <= 0 ||
        !(m.dark_share[k] >= 0.0f && m.dark_share[k] <= 1.0f)) {
      throw InputError("detections[" + std::to_string(i) + "]", "position, area or dark share out of range");
    }
  }
}

void validate(const hbirl::episode_marker_t& m) {
  using Marker = hbirl::episode_marker_t;
  if (m.kind != Marker::BEGIN_EPISODE && m.kind != Marker::BEGIN_STEP && m.kind != Marker::END_EPISODE &&
      m.kind != Marker::END_RUN) {
    throw InputError("episode_marker.kind", std::to_string(m.kind) + " is not a marker kind");
  }
  if (m.episode < 0 || m.episode >= kMaxEpisodes) throw InputError("episode_marker.episode", "out of range");
  if (m.kind == Marker::BEGIN_STEP && (m.step < 0 || m.step >= kMaxSteps))
    throw InputError("episode_marker.step", "must be in [0, " + std::to_string(kMaxSteps) + ")");
  if (m.kind != Marker::END_RUN && (m.frames_per_step < 1 || m.frames_per_step > kMaxFramesPerStep)) {
    throw InputError("episode_marker.frames_per_step", "must be in [1, " + std::to_string(kMaxFramesPerStep) + "]");
  }
  if (m.kind == Marker::END_EPISODE && (m.num_steps < 1 || m.num_steps > kMaxSteps))
    throw InputError("episode_marker.num_steps", "must be in [1, " + std::to_string(kMaxSteps) + "]");
  if (m.kind == Marker::END_RUN && m.num_steps < 0)
    throw InputError("episode_marker.num_steps", "END_RUN's number of episodes is negative");
  const bool seen_end = m.end_state_known || m.num_end_reports > 0;
  if (seen_end && !(m.kind == Marker::END_EPISODE && m.ends_in_terminal)) {
    throw InputError(m.end_state_known ? "episode_marker.end_state_known" : "episode_marker.num_end_reports",
                     "only an END_EPISODE that ended in a terminal state says how it ended");
  }
  if (m.end_state_known && m.end_state < 0) throw InputError("episode_marker.end_state", "is negative");
  if (m.num_end_symbols < 0 || m.num_end_symbols > kMaxEndSymbols)
    throw InputError("episode_marker.num_end_symbols", "must be in [0, " + std::to_string(kMaxEndSymbols) + "]");
  if (m.num_end_reports < 0 || m.num_end_reports > kMaxEndReports)
    throw InputError("episode_marker.num_end_reports", "must be in [0, " + std::to_string(kMaxEndReports) + "]");
  for (int k = 0; k < m.num_end_reports; ++k) {
    const int w = m.end_report[static_cast<size_t>(k)];
    if (w < 0 || w >= m.num_end_symbols)
      throw InputError("episode_marker.end_report[" + std::to_string(k) + "]",
                       std::to_string(w) + " is not a symbol of the end sensor's " + std::to_string(m.num_end_symbols));
  }
}

void validate(const hbirl::ground_truth_t& m) {
  if (m.episode < 0 || m.step < 0 || m.state < 0 || m.action < 0)
    throw InputError("ground_truth.step", "episode, step, state and action must be >= 0");
  if (m.episode >= kMaxEpisodes) throw InputError("ground_truth.episode", "out of range");
  if (m.step >= kMaxSteps) throw InputError("ground_truth.step", "out of range");
  if (m.num_features < 0 || m.num_features > kMaxFeatures) {
    throw InputError("ground_truth.num_features", "must be in [0, " + std::to_string(kMaxFeatures) + "]");
  }
  for (double w : m.true_weights) {
    if (!std::isfinite(w)) throw InputError("ground_truth.true_weights", "must be finite");
  }
}

namespace {

// -1 (unknown) or a finite number >= 0.
bool unknown_or_not_negative(double x) { return x == -1.0 || (std::isfinite(x) && x >= 0.0); }

}  // namespace

void validate(const hbirl::estimate_t& m) {
  if (m.demonstrations < 1 || m.demonstrations > kMaxEpisodes) {
    throw InputError("estimate.demonstrations", "must be in [1, " + std::to_string(kMaxEpisodes) + "]");
  }
  if (m.num_features < 1 || m.num_features > kMaxFeatures) {
    throw InputError("estimate.num_features", "must be in [1, " + std::to_string(kMaxFeatures) + "]");
  }
  for (double w : m.theta) {
    if (!std::isfinite(w)) throw InputError("estimate.theta", "must be finite");
  }
  if (!(m.log_likelihood <= 0.0)) throw InputError("estimate.log_likelihood", "must be a number <= 0");
  if (!(m.confidence == -1.0 || (m.confidence >= 0.0 && m.confidence <= 1.0)))
    throw InputError("estimate.confidence", "must be -1 or in [0, 1]");
  if (!unknown_or_not_negative(m.ile)) throw InputError("estimate.ile", "must be -1 or a number >= 0");
  if (!unknown_or_not_negative(m.ile_relative))
    throw InputError("estimate.ile_relative", "must be -1 or a number >= 0");
  for (const std::vector<double>& row : m.policy) {
    for (double p : row) {
      if (!(p >= 0.0 && p <= 1.0)) throw InputError("estimate.policy", "every entry must be in [0, 1]");
    }
  }
}

void validate(const hbirl::reward_t& m) {
  if (m.num_features < 1 || m.num_features > kMaxFeatures) {
    throw InputError("reward.num_features", "must be in [1, " + std::to_string(kMaxFeatures) + "]");
  }
  for (double w : m.theta) {
    if (!std::isfinite(w)) throw InputError("reward.theta", "must be finite");
  }
  if (m.num_true != 0 && m.num_true != m.num_features) {
    throw InputError("reward.num_true", "must be 0 or num_features (" + std::to_string(m.num_features) + ")");
  }
  for (double w : m.true_theta) {
    if (!std::isfinite(w)) throw InputError("reward.true_theta", "must be finite");
  }
  for (const std::vector<double>& row : m.policy) {
    for (double p : row) {
      if (!(p >= 0.0 && p <= 1.0)) throw InputError("reward.policy", "every entry must be in [0, 1]");
    }
  }
  for (std::int32_t a : m.action) {
    if (a < -1 || a >= m.num_actions) {
      throw InputError("reward.action",
                       "must be -1 (a terminal state) or in [0, " + std::to_string(m.num_actions) + ")");
    }
  }
  if (!unknown_or_not_negative(m.ile)) throw InputError("reward.ile", "must be -1 or a number >= 0");
}

void validate(const hbirl::stop_t& m) {
  if (m.demonstrations < 0 || m.demonstrations > kMaxEpisodes) {
    throw InputError("stop.demonstrations", "must be in [0, " + std::to_string(kMaxEpisodes) + "]");
  }
  if (!(m.confidence >= 0.0 && m.confidence <= 1.0)) throw InputError("stop.confidence", "must be in [0, 1]");
  if (m.reason.size() > 1000) throw InputError("stop.reason", "longer than 1000 bytes");
}

}  // namespace hbirl::services
