#pragma once
// The E-step over the bus (docs/services.md "Services and channels"): the optimiser's HiddenDataEM asks
// sampler workers, over the bus, for the statistics of the blocks of trajectories each
// is assigned, and sums them in block order -- so the learned theta is bit-identical to
// a run without workers, with 1, 2 or 4 of them, and when one dies mid-run.
//
// Protocol (channels in docs/services.md's table):
//   MDP            optimiser -> workers: the MDP's dynamics (mdp_message.hpp), with its
//                  digest. Re-sent when a worker reports another digest: workers need
//                  no domain of their own.
//   TRAJECTORY_<tag>  optimiser -> one worker (channels::trajectory_channel): the
//                  trajectories of the blocks it is assigned, as the optimiser's E-step
//                  holds them, each block known by the digest of its trajectories. Sent
//                  once: a block stays with its worker from pass to pass while the worker
//                  is live, so each worker receives and holds only its share; the blocks of
//                  a worker that dies go to the others, who are sent just those.
//   STATUS         every service, about once a second: service_status_t; a sampler's
//                  carries its MDP's digest and the digests of the blocks it holds (a
//                  block it was sent but does not hold is sent again; one a heartbeat after
//                  its sending said it did not hold, twice, goes to another worker).
//   ESTEP_REQUEST  optimiser -> workers: request id, attempt, the policy and the
//                  observation model, which worker computes which block, and each
//                  block's digest.
//   ESTEP_RESULT   worker -> optimiser: one block's statistics, echoing the request id
//                  and the block's digest.
// The optimiser waits for a block's answer up to a timeout, then re-asks it of a worker
// that has answered (a new attempt of the same request), and after max_attempts
// computes what is still missing itself: learning never stalls. Answers to other
// requests, for blocks it already has, or computed on other trajectories are counted
// and ignored. A worker answers a block once it holds the trajectories of its digest.
// Here: the optimiser's side, the pass (BusBlockExecutor), made of its parts: the messages
// both sides share (estep_wire.hpp), the workers it hears from (worker_roster.hpp), which
// block goes to which (block_placement.hpp), the paced sending of their trajectories
// (send_window.hpp) and the spot checks (worker_trust.hpp). The workers' side is
// sampler_worker.hpp.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "hbirl/estep_request_t.hpp"
#include "hbirl/estep_result_t.hpp"
#include "hbirl/service_status_t.hpp"
#include "learner/estep_observations.hpp"
#include "services/bus.hpp"
#include "services/channels.hpp"
#include "services/estep_wire.hpp"
#include "services/mdp_message.hpp"
#include "services/send_window.hpp"
#include "services/typed.hpp"
#include "services/worker_roster.hpp"
#include "services/worker_trust.hpp"

namespace hbirl::services {

// Thrown by BusBlockExecutor::run when its `stop` says so: learning ends there.
struct Stopped : std::runtime_error {
  Stopped() : std::runtime_error("stopped") {}
};

struct BusExecutorOptions {
  std::function<bool()> stop;     // checked while waiting for answers; true: run() throws Stopped
  std::function<void()> idle;     // called while waiting (the process beats its heartbeat there)
  int timeout_ms = 2000;          // wait this long without progress (an answer, a block received) before re-asking
  int max_attempts = 3;           // attempts over the bus; then the optimiser computes the rest
  double worker_silence_s = 3.0;  // workers not heard from for this long get no work
  int local_threads = 1;          // for blocks the optimiser computes itself
  // Give work only to workers whose numerics_fingerprint() equals the optimiser's: theta
  // bit-identical to a one-process run whatever machines join. Off: they all work, and
  // stats().other_numerics counts the ones that may change the last bits.
  bool same_numerics_only = false;
  // Each pass, the optimiser also computes blocks the workers were given while they
  // compute -- one block of every worker whose answers were never checked, else one block
  // chosen at random -- and compares the answers bit for bit: a worker whose block differs
  // gets no more work, is reported, and every block it answered in the pass is computed
  // here instead. So a worker that always lies is caught before any of its answers is
  // used (docs/RELIABILITY.md).
  bool spot_check = true;
  // Learned eta with more contexts than this (a sensor without contexts whose every eta
  // differs has one per observation) is not sent each pass: the optimiser computes the
  // E-step itself, and says so once.
  int max_contexts = kMaxContexts;
  // Trajectories sent to workers and not yet acknowledged (their heartbeats list the blocks
  // they hold) take at most this many bytes: on LCM's one multicast group every worker's
  // socket receives every worker's share, and a burst beyond its receive buffer
  // (recv_buf_size, 2 MB in services/launch.sh) is lost.
  std::int64_t send_window_bytes = std::int64_t{1} << 20;
};

// The optimiser's side: a BlockExecutor that farms blocks out to the workers it hears
// from. Thread-safe (one pass at a time); handles the bus while it waits, so the
// optimiser's process must not handle the same bus elsewhere at the same time.
class BusBlockExecutor final : public BlockExecutor {
 public:
  // `mdp`: what the workers are sent and must hold to get work; `domain` names it in its
  // messages. Each pass's trajectories are the E-step's own (run()): each worker is sent
  // those of its blocks when it is first given them.
  BusBlockExecutor(Bus& bus, const Mdp& mdp, const std::string& domain, Counters& counters,
                   BusExecutorOptions options = {});
  std::vector<EStepStatistics> run(const ObservationEStep& estep, const SoftSolution& policy,
                                   const ObservationModel& model, std::uint64_t seed,
                                   const RowMatrix* eta = nullptr) override;

  // Publishes the MDP now.
  void publish_mdp();
  // Handles the bus until `count` workers with this MDP are live, or timeout_ms passes;
  // returns how many are.
  int wait_for_workers(int count, int timeout_ms);

  struct Stats {
    std::int64_t requests = 0, attempts = 0, retried_blocks = 0, local_blocks = 0, remote_blocks = 0;
    std::int64_t stale = 0, duplicates = 0, foreign = 0;  // ignored answers
    std::int64_t unassigned = 0;                          // answers from a worker not given that block (refused)
    std::int64_t spot_checks = 0, liars = 0;              // blocks checked here; workers caught answering wrong
    std::int64_t conflicts =
        0;  // two different answers to a block under one name (a pass's blocks of that name computed here)
    std::int64_t other_numerics = 0;                     // workers heard from with another fingerprint (each once)
    double round_trip_s = 0.0;                           // summed over requests
    std::int64_t trajectories_sent = 0, bytes_sent = 0;  // TRAJECTORY_<tag> messages to workers, and their bytes
    // Passes that waited on a worker that had never answered (its one trial block left
    // unanswered): at most kMaxTrialPasses, whatever the number and rate of fake workers.
    std::int64_t trial_passes = 0;
    // Blocks each worker answered (and kept: answers later distrusted are taken back), by
    // its id: which workers did the E-step, whatever --workers asked for.
    std::map<std::string, std::int64_t> blocks_by_worker;
  };
  // What workers that never answer (a crashed build, a forger's heartbeats) may cost a run:
  // this many passes, each at most one timeout longer (docs/RELIABILITY.md).
  static constexpr int kMaxTrialPasses = 3;
  Stats stats() const;

 private:
  // The data set last given to workers, by blocks: the E-step it was read from, and each
  // block's digest. Read again only when the E-step is another (or holds other data).
  struct Blocks {
    const ObservationEStep* estep = nullptr;
    std::uint64_t input = 0;
    int contexts = -1;
    bool kinds = false;
    std::vector<std::uint64_t> digests;
    std::set<std::uint64_t> current;  // the same, to look up
    std::uint64_t data_digest = 0;
    bool exact = false;  // its engine is the exact one, what the workers compute with
  };
  // The pass in flight: what came back, from whom, and who was given what.
  struct Pass {
    ResultShape shape;
    std::vector<std::optional<EStepStatistics>> received;
    std::set<std::string> answered;               // workers that answered this request
    std::vector<std::set<std::string>> assigned;  // per block: the workers it was given to (any attempt)
    std::vector<std::string> answered_by;         // per block: who answered it
    std::set<std::string> doubted;                // names that gave two different answers to a block in this pass
    std::vector<int> missing() const;
  };

  void on_status(const hbirl::service_status_t& m);
  void on_result(const hbirl::estep_result_t& m);
  void take_answer(const hbirl::estep_result_t& m, EStepStatistics s);
  void prepare_blocks(const ObservationEStep& estep);
  std::vector<EStepStatistics> compute_here(const ObservationEStep& estep, const SoftSolution& policy,
                                            const ObservationModel& model, std::uint64_t seed, const RowMatrix* eta);
  std::vector<std::string> workers_for(int attempt);
  void wait_for_answers(const ObservationEStep& estep, const std::vector<std::string>& assigned);
  void judge_silence(const std::vector<std::string>& assigned);
  void check_spots(const std::vector<int>& spots, std::vector<EStepStatistics>& here,
                   const std::vector<std::string>& given);
  void distrust(const std::string& worker, const std::string& why);
  void forget_answers_of(const std::string& worker);
  int pump(const ObservationEStep& estep);

  Bus& bus_;
  std::vector<hbirl::mdp_t> mdp_messages_;
  std::uint64_t mdp_digest_;
  Counters& counters_;
  BusExecutorOptions options_;
  WorkerRoster roster_;
  SendWindow window_;
  SpotChecks spot_checks_;
  Blocks blocks_;
  // Per block: the worker it was last given to. It stays there while that worker is live
  // (place_blocks), so the worker is sent its trajectories once.
  std::vector<std::string> owners_;
  std::int64_t progress_ = 0;  // answers taken and blocks acknowledged: what keeps a pass waiting
  std::chrono::steady_clock::time_point last_mdp_sent_{};
  std::int64_t request_id_ = 0;
  Pass pass_;
  bool said_too_many_contexts_ = false;
  Stats stats_;
  mutable std::recursive_mutex mutex_;  // handlers run inside run() with it held; stats() reads under it
  Subscriptions subs_;                  // last: ends first
};

}  // namespace hbirl::services
