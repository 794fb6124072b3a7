#include "services/send_window.hpp"

#include <algorithm>

#include "services/channels.hpp"
#include "services/estep_wire.hpp"

namespace hbirl::services {

SendWindow::SendWindow(Bus& bus, Counters& counters, std::int64_t window_bytes, std::chrono::milliseconds resend_after)
    : bus_(bus), counters_(counters), window_bytes_(window_bytes), resend_after_(resend_after) {}

void SendWindow::queue(const std::vector<int>& todo, const std::vector<std::string>& assigned,
                       const std::vector<std::uint64_t>& digests, WorkerRoster& roster) {
  const auto now = Worker::Clock::now();
  queued_.clear();
  for (int b : todo) {
    const std::string& id = assigned[static_cast<size_t>(b)];
    if (id.empty()) continue;
    Worker& w = roster[id];
    const std::uint64_t digest = digests[static_cast<size_t>(b)];
    if (w.held.count(digest)) continue;
    const auto sent = w.sent.find(digest);
    if (sent != w.sent.end() && now - sent->second.when < resend_after_) continue;
    queued_.emplace_back(b, id);
  }
}

int SendWindow::pump(const ObservationEStep& estep, const std::vector<std::uint64_t>& digests, WorkerRoster& roster) {
  if (queued_.empty()) return 0;
  std::int64_t in_flight = roster.bytes_in_flight(resend_after_);
  const int n = static_cast<int>(estep.trajectories().size());
  size_t k = 0;
  for (; k < queued_.size() && (in_flight == 0 || in_flight < window_bytes_); ++k) {
    const auto& [b, id] = queued_[k];
    const std::uint64_t digest = digests[static_cast<size_t>(b)];
    const Channel<hbirl::trajectory_t> channel = channels::trajectory_channel(id);
    std::int64_t bytes = 0;
    const int end = std::min(n, (b + 1) * ObservationEStep::kBlockSize);
    for (int i = b * ObservationEStep::kBlockSize; i < end; ++i) {
      const hbirl::trajectory_t m = to_message(estep.trajectories()[static_cast<size_t>(i)], i, n, digest, id);
      publish(bus_, channel, m, counters_);
      bytes += m.getEncodedSize();
    }
    trajectories_sent_ += end - b * ObservationEStep::kBlockSize;
    bytes_sent_ += bytes;
    roster[id].sent[digest] = {Worker::Clock::now(), bytes};
    in_flight += bytes;
  }
  queued_.erase(queued_.begin(), queued_.begin() + static_cast<std::ptrdiff_t>(k));
  return static_cast<int>(k);
}

std::set<std::string> SendWindow::drop() {
  std::set<std::string> workers;
  for (const auto& [b, id] : queued_) workers.insert(id);
  queued_.clear();
  return workers;
}

}  // namespace hbirl::services
