#pragma once
// What the fuzz targets share: the channels of the service set with their message types
// (in one fixed order, so that one input byte names a channel), and the framing by which
// one fuzz input carries several bus messages.
#include <cstddef>
#include <cstdint>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "hbirl/camera_frame_t.hpp"
#include "hbirl/detections_t.hpp"
#include "hbirl/em_progress_t.hpp"
#include "hbirl/episode_marker_t.hpp"
#include "hbirl/estimate_t.hpp"
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
#include "services/channels.hpp"

namespace hbirl::fuzz {

// Channel k carries Types' k-th type. The order is part of the seed corpora's format:
// append, never reorder.
using Types =
    std::tuple<hbirl::camera_frame_t, hbirl::detections_t, hbirl::observations_t, hbirl::episode_marker_t,
               hbirl::ground_truth_t, hbirl::mdp_t, hbirl::trajectory_t, hbirl::estep_request_t, hbirl::estep_result_t,
               hbirl::em_progress_t, hbirl::observation_model_t, hbirl::posterior_t, hbirl::reward_t,
               hbirl::frame_request_t, hbirl::service_status_t, hbirl::estimate_t, hbirl::stop_t>;
constexpr int kNumChannels = static_cast<int>(std::tuple_size_v<Types>);

// The id of the sampler worker the service-handler fuzzer runs (and the seeds address).
inline const std::string kFuzzSampler = "sampler-fuzz";

inline const std::string& channel(int k) {
  namespace ch = services::channels;
  // Trajectories go to one sampler's own channel: the fuzzed one's (fuzz_service_handlers).
  static const std::string trajectories = ch::trajectory_channel(kFuzzSampler).name;
  static const std::string* const names[] = {&ch::kCamera.name,
                                             &ch::kDetections.name,
                                             &ch::kObservations.name,
                                             &ch::kEpisode.name,
                                             &ch::kGroundTruth.name,
                                             &ch::kMdp.name,
                                             &trajectories,
                                             &ch::kEStepRequest.name,
                                             &ch::kEStepResult.name,
                                             &ch::kEmProgress.name,
                                             &ch::kObservationModel.name,
                                             &ch::kPosterior.name,
                                             &ch::kReward.name,
                                             &ch::kFrameRequest.name,
                                             &ch::kStatus.name,
                                             &ch::kEstimate.name,
                                             &ch::kStop.name};
  static_assert(sizeof(names) / sizeof(names[0]) == kNumChannels);
  return *names[k];
}

// Calls f(T{}) with the k-th type (0 <= k < kNumChannels).
template <class F, std::size_t... I>
void with_type_impl(int k, F&& f, std::index_sequence<I...>) {
  ((k == static_cast<int>(I) ? (f(std::tuple_element_t<I, Types>{}), 0) : 0), ...);
}
template <class F>
void with_type(int k, F&& f) {
  with_type_impl(k, std::forward<F>(f), std::make_index_sequence<kNumChannels>{});
}

// One message of a multi-message input.
struct Record {
  int channel;  // 0 <= channel < kNumChannels
  const std::uint8_t* data;
  int size;
};

// The framing of a multi-message input: records of
//   [channel byte (mod kNumChannels)] [size: 2 bytes, big-endian] [size bytes]
// in a row; a last record shorter than its size takes what is left. Simple enough that
// the fuzzer's mutations move between whole messages and the bytes inside them.
inline std::vector<Record> split_records(const std::uint8_t* data, std::size_t size, std::size_t max_records = 64) {
  std::vector<Record> out;
  std::size_t pos = 0;
  while (pos < size && out.size() < max_records) {
    const int ch = data[pos] % kNumChannels;
    std::size_t n = 0;
    if (pos + 3 <= size) n = static_cast<std::size_t>(data[pos + 1]) << 8 | data[pos + 2];
    pos = std::min(pos + 3, size);
    n = std::min(n, size - pos);
    out.push_back({ch, data + pos, static_cast<int>(n)});
    pos += n;
  }
  return out;
}

// The record header for `size` bytes on channel k (the seed generator's side).
inline std::vector<std::uint8_t> record(int k, const std::vector<std::uint8_t>& bytes) {
  std::vector<std::uint8_t> out{static_cast<std::uint8_t>(k), static_cast<std::uint8_t>(bytes.size() >> 8),
                                static_cast<std::uint8_t>(bytes.size() & 0xff)};
  out.insert(out.end(), bytes.begin(), bytes.end());
  return out;
}

}  // namespace hbirl::fuzz
