#pragma once
// The trajectories an optimiser sends its sampler workers (estep_service.hpp), paced: bytes
// sent and not yet acknowledged by a heartbeat stay under a window. On LCM's one multicast
// group every worker's socket receives every worker's share, and a burst beyond its
// receive buffer (recv_buf_size, 2 MB in services/launch.sh) is lost.
#include <chrono>
#include <cstdint>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "learner/estep_observations.hpp"
#include "services/bus.hpp"
#include "services/typed.hpp"
#include "services/worker_roster.hpp"

namespace hbirl::services {

class SendWindow {
 public:
  // A block sent `resend_after` ago and not acknowledged is taken as lost.
  SendWindow(Bus& bus, Counters& counters, std::int64_t window_bytes, std::chrono::milliseconds resend_after);

  // Queues each block of `todo` for the worker `assigned` to it, unless that worker holds it
  // (its heartbeat says so) or was sent it less than `resend_after` ago. Replaces the queue.
  void queue(const std::vector<int>& todo, const std::vector<std::string>& assigned,
             const std::vector<std::uint64_t>& digests, WorkerRoster& roster);
  // Sends queued blocks while the window has room (one block at least when nothing is in
  // flight, whatever its size); returns how many it sent.
  int pump(const ObservationEStep& estep, const std::vector<std::uint64_t>& digests, WorkerRoster& roster);
  // Empties the queue; returns the workers whose blocks were still in it.
  std::set<std::string> drop();

  std::int64_t trajectories_sent() const { return trajectories_sent_; }
  std::int64_t bytes_sent() const { return bytes_sent_; }

 private:
  Bus& bus_;
  Counters& counters_;
  std::int64_t window_bytes_;
  std::chrono::milliseconds resend_after_;
  std::vector<std::pair<int, std::string>> queued_;  // (block, worker), in order
  std::int64_t trajectories_sent_ = 0, bytes_sent_ = 0;
};

}  // namespace hbirl::services
