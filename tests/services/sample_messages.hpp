#pragma once
// One valid message of every type on every channel, each with every variable-length
// array and string non-empty, so that every length field is present in its bytes: the
// material of the hostile-length tests (a decoder must refuse, not crash or balloon, when
// any 4 bytes of a message are replaced by a hostile length), of lcm_inject and of the
// fuzzers' seed corpora (docs/RELIABILITY.md).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hbirl/camera_frame_t.hpp"
#include "hbirl/detections_t.hpp"
#include "hbirl/em_progress_t.hpp"
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
#include "hbirl/estimate_t.hpp"
#include "hbirl/stop_t.hpp"
#include "hbirl/service_status_t.hpp"
#include "hbirl/trajectory_t.hpp"

namespace hbirl::test {

struct SampleMessage {
  std::string channel;
  std::string type;
  std::vector<std::uint8_t> bytes;
  // Decodes bytes as this type into a fresh message and returns what the receiver's
  // decode() returns; `while_decoded` (if any) runs while that message still holds what the
  // decode allocated.
  std::function<int(const std::uint8_t*, int, const std::function<void()>&)> decode;
};

template <class T>
SampleMessage sample_of(const std::string& channel, const T& msg) {
  SampleMessage s{channel, T::getTypeName(), std::vector<std::uint8_t>(static_cast<size_t>(msg.getEncodedSize())),
                  [](const std::uint8_t* data, int size, const std::function<void()>& while_decoded) {
                    T out;
                    const int used = out.decode(data, 0, size);
                    if (while_decoded) while_decoded();
                    return used;
                  }};
  msg.encode(s.bytes.data(), 0, static_cast<int>(s.bytes.size()));
  return s;
}

inline std::vector<SampleMessage> sample_messages() {
  std::vector<SampleMessage> all;
  {
    hbirl::camera_frame_t m{};
    m.width = 2, m.height = 1, m.encoding = "png", m.size = 3, m.data = {1, 2, 3};
    all.push_back(sample_of("CAMERA", m));
  }
  {
    hbirl::detections_t m{};
    m.n = 2;
    m.cls = {0, 1}, m.x = {1, 2}, m.y = {3, 4}, m.area = {5, 6}, m.box_x = {1, 1}, m.box_y = {1, 1}, m.box_w = {2, 2},
    m.box_h = {2, 2}, m.dark_share = {0.5f, 0.25f};
    all.push_back(sample_of("DETECTIONS", m));
  }
  {
    hbirl::observations_t m{};
    m.num_symbols = 4, m.num_sources = 2, m.n = 2, m.symbol = {1, 3}, m.eta = {{0.9, 0.1}, {0.5, 0.5}};
    m.num_context = 2, m.context = {0, 19};
    all.push_back(sample_of("OBSERVATIONS", m));
  }
  {
    hbirl::episode_marker_t m{};
    m.domain = "onion", m.kind = hbirl::episode_marker_t::END_EPISODE, m.num_steps = 3, m.frames_per_step = 2;
    all.push_back(sample_of("EPISODE", m));
  }
  {
    hbirl::ground_truth_t m{};
    m.domain = "gridworld", m.state = 1, m.action = 2, m.num_features = 2, m.true_weights = {1, -1};
    all.push_back(sample_of("GROUND_TRUTH", m));
  }
  {
    hbirl::mdp_t m{};
    m.domain = "warehouse", m.num_chunks = 1, m.num_states = 2, m.num_actions = 1, m.discount = 0.9, m.num_start = 2,
    m.start = {1, 0}, m.terminal = {false, true}, m.num_transitions = 2, m.pair = {0, 1}, m.next_state = {1, 1},
    m.probability = {1, 1};
    all.push_back(sample_of("MDP", m));
  }
  {
    hbirl::trajectory_t m{};
    m.block_digest = 9, m.index = 0, m.num_trajectories = 1, m.block_size = 16, m.worker = "sampler-a", m.num_steps = 2,
    m.step_begin = {0, 1}, m.n = 2, m.symbol = {0, 1}, m.num_sources = 2, m.eta = {{1, 0}, {0.5, 0.5}},
    m.num_weights = 2, m.weights = {1, 2};
    m.num_context = 2, m.context = {1, 0};
    all.push_back(sample_of("TRAJECTORY", m));
  }
  {
    hbirl::estep_request_t m{};
    m.request_id = 7, m.num_trajectories = 1, m.block_size = 1, m.num_blocks = 2,
    m.assigned_worker = {"sampler-a", "b"};
    m.block_digest = {3, 4}, m.kind_table = true;
    m.engine = "exact", m.watch = -1, m.num_pairs = 2, m.log_policy = {0, 0}, m.policy = {1, 1}, m.num_symbols = 2,
    m.num_confounders = 1, m.subject_o = {{0.5, 0.5}, {0.5, 0.5}}, m.confounder_o = {{0.5, 0.5}};
    m.num_contexts = 2, m.num_sources = 2, m.context_eta = {{0.8, 0.2}, {0.3, 0.7}};
    all.push_back(sample_of("ESTEP_REQUEST", m));
  }
  {
    hbirl::estep_result_t m{};
    m.request_id = 7, m.worker = "sampler-a", m.block_digest = 3, m.num_pairs = 2, m.counts = {1, 2}, m.num_symbols = 2,
    m.num_confounders = 1, m.alpha_subject = {{1, 0}, {0, 1}}, m.alpha_confounder = {{1, 1}}, m.num_watched_steps = 1,
    m.watched = {{0.5, 0.5}};
    m.num_contexts = 2, m.num_sources = 2, m.source_counts = {{1.5, 0.5}, {0, 2}};
    all.push_back(sample_of("ESTEP_RESULT", m));
  }
  {
    hbirl::em_progress_t m{};
    m.num_features = 2, m.theta = {1, 2};
    all.push_back(sample_of("EM_PROGRESS", m));
  }
  {
    hbirl::observation_model_t m{};
    m.domain = "onion", m.num_states = 1, m.num_actions = 2, m.num_pairs = 2, m.num_symbols = 2, m.num_confounders = 1,
    m.subject = {{1, 0}, {0, 1}}, m.confounders = {{0.5, 0.5}};
    m.num_contexts = 1, m.num_sources = 2, m.stated_eta = {{0.8, 0.2}}, m.learned_eta = {{0.6, 0.4}},
    m.context_observations = {3};
    all.push_back(sample_of("OBSERVATION_MODEL", m));
  }
  {
    hbirl::posterior_t m{};
    m.domain = "onion", m.num_steps = 2, m.num_states = 1, m.num_actions = 2, m.num_pairs = 2,
    m.marginals = {{0.5, 0.5}, {1, 0}};
    all.push_back(sample_of("POSTERIOR", m));
  }
  {
    hbirl::reward_t m{};
    m.domain = "onion", m.num_features = 2, m.theta = {1, 2}, m.num_true = 2, m.true_theta = {1, 1}, m.num_states = 1,
    m.num_actions = 2, m.policy = {{0.5, 0.5}}, m.action = {1};
    all.push_back(sample_of("REWARD", m));
  }
  {
    hbirl::frame_request_t m{};
    m.requester = "optimiser", m.n = 2, m.episode = {0, 1}, m.step = {2, 3}, m.frame = {0, 0};
    all.push_back(sample_of("FRAME_REQUEST", m));
  }
  {
    hbirl::service_status_t m{};
    m.service = "sampler", m.id = "sampler-x-1", m.state = "running", m.detail = "fine";
    m.num_held_blocks = 2, m.held_block = {3, 4};
    all.push_back(sample_of("STATUS", m));
  }
  {
    hbirl::estimate_t m{};
    m.domain = "onion", m.demonstrations = 2, m.num_features = 2, m.theta = {1, 2}, m.log_likelihood = -3,
    m.confidence = 0.9, m.ile = m.ile_relative = 0, m.num_states = 1, m.num_actions = 2, m.policy = {{0.5, 0.5}};
    all.push_back(sample_of("ESTIMATE", m));
  }
  {
    hbirl::stop_t m{};
    m.domain = "onion", m.reason = "seen enough", m.demonstrations = 4, m.confidence = 0.96;
    all.push_back(sample_of("STOP", m));
  }
  return all;
}

// The length fields a hostile sender writes: below zero (INT_MIN wraps a string copy in an
// unpatched decoder), zero, and far more than the bytes that follow.
inline const std::vector<std::int32_t>& hostile_lengths() {
  static const std::vector<std::int32_t> lengths{INT32_MIN, -1, 0, 1 << 20, 0x10000000, INT32_MAX};
  return lengths;
}

// `bytes` with the big-endian int32 `value` written at `offset` (LCM's byte order).
inline std::vector<std::uint8_t> with_int32_at(std::vector<std::uint8_t> bytes, size_t offset, std::int32_t value) {
  const auto u = static_cast<std::uint32_t>(value);
  for (int k = 0; k < 4; ++k) bytes[offset + static_cast<size_t>(k)] = static_cast<std::uint8_t>(u >> (24 - 8 * k));
  return bytes;
}

}  // namespace hbirl::test
