#pragma once
// The sampler workers an optimiser hears from (the E-step's protocol: estep_service.hpp),
// and what it knows of each: its MDP and numerics, the blocks it holds and was sent, when
// it was last heard, whether it answers and whether it is trusted. Fed by their heartbeats;
// a name made up on the bus costs one entry, and at most kMaxWorkers are remembered.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "hbirl/service_status_t.hpp"

namespace hbirl::services {

struct Worker {
  using Clock = std::chrono::steady_clock;
  std::uint64_t mdp_digest = 0;
  std::set<std::uint64_t> held;  // the blocks it holds (their digests), as its last heartbeat said
  struct Sent {
    Clock::time_point when;
    std::int64_t bytes = 0;
  };
  std::map<std::uint64_t, Sent> sent;  // blocks sent to it, not yet seen held
  Clock::time_point last_seen;
  std::uint64_t numerics = 0;
  bool suspect = false;  // left blocks unanswered; gets work again once heard from (a heartbeat after suspect_since)
  Clock::time_point suspect_since;
  bool distrusted = false;     // answered a spot-checked block wrong: no more work while it is remembered
  std::int64_t answers = 0;    // blocks it answered: a worker that never did gets little work
  bool ever_answered = false;  // answered a block in this run (answers is reset by silence, this is not)
  bool checked = false;        // one of its answers matched the optimiser's own computation
  // Per block sent to it: how many heartbeats after its sending said it was not held (lost
  // on the way, or refused: over its --max-dataset-mb, a digest that did not match). Twice,
  // and the block goes to other workers (for this data set, and for a minute after the
  // last such failure, lest a lossy start keep a worker out for good).
  std::map<std::uint64_t, int> unheld;
  Clock::time_point last_unheld;

  bool can_hold(std::uint64_t digest) const {
    const auto it = unheld.find(digest);
    return it == unheld.end() || it->second < 2;
  }
  int blocks_it_cannot_hold() const {
    return static_cast<int>(std::count_if(unheld.begin(), unheld.end(), [](const auto& u) { return u.second >= 2; }));
  }
  // Left blocks of a pass unanswered: no more work until it is heard from again, and then
  // one block until it answers.
  void suspect_now() {
    suspect = true;
    suspect_since = Clock::now();
    answers = 0;
  }
};

class WorkerRoster {
 public:
  using Clock = Worker::Clock;
  static constexpr size_t kMaxWorkers = 4096;  // workers remembered at once (a sender can make up any number of names)

  // Workers with this MDP and (when `same_numerics_only`) these numerics get work, while
  // heard from within `silence_s`.
  WorkerRoster(std::uint64_t mdp_digest, std::uint64_t numerics, bool same_numerics_only, double silence_s);

  // What a heartbeat changed.
  struct Heard {
    std::int64_t acknowledged = 0;  // blocks sent to it that it now holds
    bool needs_mdp = false;         // it holds another MDP
    bool new_numerics = false;      // first heard with numerics other than the optimiser's
  };
  // A sampler's heartbeat; only blocks of `current` (this data set's) are remembered held.
  Heard hear(const hbirl::service_status_t& m, const std::set<std::uint64_t>& current);
  // The workers that get work now, in name order. Workers that never answered only while
  // `trials` (the run's budget of passes waiting on them lasts).
  std::vector<std::string> live(bool trials) const;
  // A new data set: what each could not hold was of the last one.
  void new_data_set();
  // Bytes sent that no heartbeat has acknowledged yet, less than `lost_after` ago.
  std::int64_t bytes_in_flight(std::chrono::milliseconds lost_after) const;

  Worker& operator[](const std::string& id) { return workers_[id]; }
  Worker* find(const std::string& id);
  std::uint64_t numerics() const { return numerics_; }

 private:
  std::uint64_t mdp_digest_, numerics_;
  bool same_numerics_only_;
  double silence_s_;
  std::map<std::string, Worker> workers_;
  std::set<std::string> other_numerics_;  // workers reported with another fingerprint
};

}  // namespace hbirl::services
