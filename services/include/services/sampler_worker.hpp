#pragma once
// The sampler worker service (hbirl-sampler; the protocol: estep_service.hpp): it learns
// the MDP from the bus and, on a channel of its own, the trajectories of the blocks it is
// assigned, and computes those blocks' E-step statistics.
#include <atomic>
#include <chrono>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "services/estep_service.hpp"
#include "services/mdp_message.hpp"

namespace hbirl::services {

// A sampler worker: holds its share of the optimiser's data set -- the blocks it is
// assigned, each known by its digest -- and answers E-step requests for them. Its E-step
// over those blocks gives each block's statistics bit for bit as the optimiser's E-step
// over the whole data set would (ObservationEStepOptions::kind_table). Call handle() from
// one thread; it also sends the heartbeat.
class SamplerWorker {
 public:
  // The most memory the blocks held and being received may take (hbirl-sampler
  // --max-dataset-mb): a TRAJECTORY that would take them past this is refused (held blocks
  // no longer assigned to it are dropped first), so no sender can make a worker allocate
  // more (docs/RELIABILITY.md).
  static constexpr std::int64_t kDefaultMaxDatasetBytes = std::int64_t{2048} << 20;

  // It learns the MDP from the bus (MDP) and its blocks (TRAJECTORY_<tag of id>).
  SamplerWorker(Bus& bus, std::string id, Counters& counters, std::int64_t max_dataset_bytes = kDefaultMaxDatasetBytes);
  // Handles what the bus has (waiting up to timeout_ms) and publishes the heartbeat when
  // one is due. Returns the bus's answer (-1: the bus has ended).
  int handle(int timeout_ms);
  // The heartbeat; `state` overrides "starting"/"running" (e.g. "done" on the way out).
  void publish_status(const std::string& state = "");
  const std::string& id() const { return id_; }
  std::uint64_t mdp_digest() const { return mdp_digest_; }
  std::int64_t blocks_computed() const { return blocks_computed_; }
  // The trajectories it holds, and the bytes of the TRAJECTORY messages it was sent (read
  // by tests from another thread).
  int trajectories_held() const { return trajectories_held_; }
  std::int64_t trajectory_bytes_received() const { return trajectory_bytes_; }
  // Testing: every answer from now on has 1 added to its first count -- a worker that lies
  // (or a broken build), for the optimiser's spot check to catch.
  void lie_for_testing() { lying_ = true; }

 private:
  struct Incoming {  // a block being received: by position, only what has arrived takes memory
    int size = 0;
    std::map<int, ObservedTrajectory> trajectories;
  };
  void on_mdp(const hbirl::mdp_t& m);
  void on_trajectory(const hbirl::trajectory_t& m, int bytes);
  void on_request(const hbirl::estep_request_t& m, std::uint64_t run);
  // Computes the blocks of the pending request whose trajectories are here (all of them
  // when `all_here_only` says to wait until every one is).
  void serve(bool all_here_only);
  void check_request(const hbirl::estep_request_t& m) const;
  void drop_unassigned(bool incoming_too);
  void release(std::uint64_t digest);
  void held_changed();
  // The trajectories of a held block, whether in held_ or lent to the E-step (0: not held).
  size_t held_size(std::uint64_t digest) const;
  // The E-step takes the blocks it computes from held_ (gather) and gives them back when it
  // is made again or goes (take_back_lent): each trajectory is held once (issue 35).
  std::vector<ObservedTrajectory> gather(const std::vector<std::pair<int, std::uint64_t>>& blocks, size_t trajectories);
  void give_back(std::vector<ObservedTrajectory>&& data, const std::vector<std::pair<int, std::uint64_t>>& blocks);
  void take_back_lent();

  Bus& bus_;
  MdpAssembler incoming_mdp_;
  std::optional<Mdp> mdp_;
  std::atomic<std::uint64_t> mdp_digest_{0};  // read by tests from another thread
  std::string id_;
  Counters& counters_;
  std::int64_t max_dataset_bytes_;
  // The blocks held, by digest, and the bytes they and the incoming ones take. A block the
  // E-step holds keeps its place here, empty, with its size in lent_.
  std::map<std::uint64_t, std::vector<ObservedTrajectory>> held_;
  std::map<std::uint64_t, size_t> lent_;
  std::map<std::uint64_t, Incoming> incoming_;
  std::int64_t bytes_ = 0;
  std::map<std::uint64_t, std::int64_t> block_bytes_;
  std::atomic<int> trajectories_held_{0};
  std::atomic<std::int64_t> trajectory_bytes_{0};
  std::chrono::steady_clock::time_point last_trajectory_{};
  // The blocks (index -> digest) its last first-attempt request gave it, and what is asked
  // of it and not answered yet: the request and its blocks.
  std::map<int, std::uint64_t> assigned_;
  std::optional<hbirl::estep_request_t> request_;
  std::uint64_t request_run_ = 0;  // the run it was signed for (keyed_bus.hpp), whose answers it gets
  std::set<int> pending_;
  std::uint64_t last_dataset_digest_ = 0;
  // The E-step over the blocks it computes, and what it was made for.
  std::optional<ObservationEStep> estep_;
  std::vector<std::pair<int, std::uint64_t>> estep_blocks_;
  std::tuple<int, int, int, bool, int, bool, int, int> estep_shape_{};
  std::set<std::pair<std::int64_t, int>> answered_;  // (request id, attempt): idempotent
  std::atomic<std::int64_t> blocks_computed_{0};
  std::int64_t status_seq_ = 0;
  bool lying_ = false;
  std::chrono::steady_clock::time_point next_status_{};
  std::chrono::steady_clock::time_point last_status_{};
  // The next heartbeat within 100 ms of the last (not one per message: junk cannot make it
  // a flood): after a block is refused, so that the optimiser stops waiting for it.
  void status_soon();
  Subscriptions subs_;  // last: ends first
};

}  // namespace hbirl::services
