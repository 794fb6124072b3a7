#include "services/worker_roster.hpp"

#include "learner/input_error.hpp"

namespace hbirl::services {

WorkerRoster::WorkerRoster(std::uint64_t mdp_digest, std::uint64_t numerics, bool same_numerics_only, double silence_s)
    : mdp_digest_(mdp_digest), numerics_(numerics), same_numerics_only_(same_numerics_only), silence_s_(silence_s) {}

WorkerRoster::Heard WorkerRoster::hear(const hbirl::service_status_t& m, const std::set<std::uint64_t>& current) {
  Heard heard;
  if (m.service != "sampler") return heard;
  if (m.id.empty()) throw InputError("status.id", "is empty");
  if (m.state == "done") {  // a worker on its way out: no more work for it
    workers_.erase(m.id);
    return heard;
  }
  if (!workers_.count(m.id) && workers_.size() >= kMaxWorkers) {
    // Heartbeats under ever new names: forget the longest silent of those that never
    // answered (a worker that did, busy computing now, is not pushed out by made-up names).
    const auto older = [](const auto& a, const auto& b) {
      return std::pair(a.second.ever_answered, a.second.last_seen) <
             std::pair(b.second.ever_answered, b.second.last_seen);
    };
    workers_.erase(std::min_element(workers_.begin(), workers_.end(), older));
  }
  Worker& w = workers_[m.id];
  w.mdp_digest = static_cast<std::uint64_t>(m.mdp_digest);
  w.held.clear();
  for (const std::int64_t d : m.held_block) {  // only this data set's blocks: a made-up list takes no memory
    if (!current.count(static_cast<std::uint64_t>(d))) continue;
    w.held.insert(static_cast<std::uint64_t>(d));
    heard.acknowledged += static_cast<std::int64_t>(w.sent.erase(static_cast<std::uint64_t>(d)));
  }
  // Heard from after it left blocks unanswered: work again, one block until it answers.
  if (w.suspect && Clock::now() > w.suspect_since) w.suspect = false;
  w.last_seen = Clock::now();
  w.numerics = static_cast<std::uint64_t>(m.numerics);
  heard.new_numerics = w.numerics != numerics_ && other_numerics_.insert(m.id).second;
  heard.needs_mdp = w.mdp_digest != mdp_digest_;
  return heard;
}

std::vector<std::string> WorkerRoster::live(bool trials) const {
  std::vector<std::string> out;
  const auto now = Clock::now();
  for (const auto& [id, w] : workers_) {
    if (w.mdp_digest == mdp_digest_ && !w.suspect && !w.distrusted && (trials || w.ever_answered) &&
        (!same_numerics_only_ || w.numerics == numerics_) &&
        std::chrono::duration<double>(now - w.last_seen).count() <= silence_s_) {
      out.push_back(id);
    }
  }
  return out;  // sorted: std::map
}

void WorkerRoster::new_data_set() {
  for (auto& [id, w] : workers_) w.unheld.clear();
}

std::int64_t WorkerRoster::bytes_in_flight(std::chrono::milliseconds lost_after) const {
  const auto now = Clock::now();
  std::int64_t bytes = 0;
  for (const auto& [id, w] : workers_) {
    for (const auto& [digest, sent] : w.sent) {
      if (now - sent.when < lost_after) bytes += sent.bytes;
    }
  }
  return bytes;
}

Worker* WorkerRoster::find(const std::string& id) {
  const auto it = workers_.find(id);
  return it == workers_.end() ? nullptr : &it->second;
}

}  // namespace hbirl::services
