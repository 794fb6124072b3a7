#pragma once
// The sampler worker service (hbirl-sampler; the protocol: estep_service.hpp): it learns
// the MDP and the data set from the bus and computes the E-step blocks it is assigned.
#include <atomic>
#include <chrono>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "services/estep_service.hpp"
#include "services/mdp_message.hpp"

namespace hbirl::services {

// A sampler worker: holds the optimiser's data set and answers E-step requests for the
// blocks assigned to it. Call handle() from one thread; it also sends the heartbeat.
class SamplerWorker {
 public:
  // The most memory the data set being received may take (hbirl-sampler --max-dataset-mb):
  // a TRAJECTORY that would take it past this is refused and the partial set dropped, so
  // no sender can make a worker allocate more (docs/RELIABILITY.md).
  static constexpr std::int64_t kDefaultMaxDatasetBytes = std::int64_t{2048} << 20;

  // It learns the MDP from the bus (MDP) and the data set (TRAJECTORY).
  SamplerWorker(Bus& bus, std::string id, Counters& counters, std::int64_t max_dataset_bytes = kDefaultMaxDatasetBytes);
  // Handles what the bus has (waiting up to timeout_ms) and publishes the heartbeat when
  // one is due. Returns the bus's answer (-1: the bus has ended).
  int handle(int timeout_ms);
  // The heartbeat; `state` overrides "starting"/"running" (e.g. "done" on the way out).
  void publish_status(const std::string& state = "");
  const std::string& id() const { return id_; }
  std::uint64_t digest() const { return digest_; }
  std::uint64_t mdp_digest() const { return mdp_digest_; }
  std::int64_t blocks_computed() const { return blocks_computed_; }
  // Testing: every answer from now on has 1 added to its first count -- a worker that lies
  // (or a broken build), for the optimiser's spot check to catch.
  void lie_for_testing() { lying_ = true; }

 private:
  void on_mdp(const hbirl::mdp_t& m);
  void on_trajectory(const hbirl::trajectory_t& m);
  void on_request(const hbirl::estep_request_t& m);

  Bus& bus_;
  MdpAssembler incoming_mdp_;
  std::optional<Mdp> mdp_;
  std::atomic<std::uint64_t> mdp_digest_{0};  // read by tests from another thread
  std::string id_;
  Counters& counters_;
  // The data set being received (by index: only what has arrived takes memory, whatever
  // size it declares), its declared size and bytes so far, and the complete one.
  std::uint64_t incoming_digest_ = 0;
  int incoming_size_ = 0;
  std::int64_t incoming_bytes_ = 0;
  std::int64_t max_dataset_bytes_;
  std::map<int, ObservedTrajectory> incoming_;
  std::vector<ObservedTrajectory> trajectories_;
  std::atomic<std::uint64_t> digest_{0};  // read by tests from another thread
  int max_symbol_ = -1;
  std::optional<ObservationEStep> estep_;
  int estep_symbols_ = -1, estep_confounders_ = -1;
  std::set<std::pair<std::int64_t, int>> answered_;  // (request id, attempt): idempotent
  std::atomic<std::int64_t> blocks_computed_{0};
  std::int64_t status_seq_ = 0;
  bool lying_ = false;
  std::chrono::steady_clock::time_point next_status_{};
  Subscriptions subs_;  // last: ends first
};

}  // namespace hbirl::services
