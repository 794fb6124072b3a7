#include "services/block_placement.hpp"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <map>

namespace hbirl::services {

std::vector<std::string> place_blocks(const std::vector<int>& todo, std::vector<std::string> workers,
                                      const std::vector<std::uint64_t>& digests, std::vector<std::string>& owners,
                                      WorkerRoster& roster) {
  for (const auto& w : workers) {  // failures to hold are forgotten a minute after the last
    Worker& x = roster[w];
    if (!x.unheld.empty() && Worker::Clock::now() - x.last_unheld > std::chrono::minutes(1)) x.unheld.clear();
  }
  const auto can_hold = [&](const std::string& w, int b) {
    return roster[w].can_hold(digests[static_cast<size_t>(b)]);
  };
  // A worker that failed to hold two blocks and holds none gets no more (for this data set,
  // or until the minute above passes): each block it is given would cost the pass a timeout.
  workers.erase(std::remove_if(workers.begin(), workers.end(),
                               [&roster](const std::string& w) {
                                 const Worker& x = roster[w];
                                 return x.blocks_it_cannot_hold() >= 2 && x.held.empty();
                               }),
                workers.end());
  std::vector<std::string> proven, unproven;
  for (const auto& w : workers) (roster[w].answers > 0 ? proven : unproven).push_back(w);
  std::vector<std::string> out(digests.size());
  std::vector<int> rest = todo;
  if (!proven.empty()) {
    unproven.resize(std::min(unproven.size(), proven.size()));
    for (const auto& w : unproven) {  // the block it has, else the last one; either one it can hold
      if (rest.empty()) break;
      auto pick = std::find_if(rest.begin(), rest.end(),
                               [&](int b) { return owners[static_cast<size_t>(b)] == w && can_hold(w, b); });
      if (pick == rest.end()) {
        const auto last = std::find_if(rest.rbegin(), rest.rend(), [&](int b) { return can_hold(w, b); });
        if (last == rest.rend()) continue;
        pick = std::prev(last.base());
      }
      out[static_cast<size_t>(*pick)] = w;
      rest.erase(pick);
    }
    workers = proven;
  }
  const size_t n = workers.size();
  std::map<std::string, size_t> share, given;  // even shares, the first ones one larger
  for (size_t k = 0; k < n; ++k)
    share[workers[k]] = rest.size() / n + (k < rest.size() % n ? 1 : 0);  // none: all loose
  std::vector<int> loose;
  for (int b : rest) {
    const std::string& owner = owners[static_cast<size_t>(b)];
    const auto it = share.find(owner);
    if (it != share.end() && given[owner] < it->second && can_hold(owner, b)) {
      out[static_cast<size_t>(b)] = owner;
      ++given[owner];
    } else {
      loose.push_back(b);
    }
  }
  for (int b : loose) {  // the first worker under its share that can hold it, else the least loaded that can
    std::string pick;
    for (const auto& w : workers) {
      if (!can_hold(w, b)) continue;
      if (given[w] < share[w]) {
        pick = w;
        break;
      }
      if (pick.empty() || given[w] < given[pick]) pick = w;
    }
    if (pick.empty()) continue;  // no worker can: computed here
    out[static_cast<size_t>(b)] = pick;
    ++given[pick];
  }
  for (int b : todo) {  // a block moved: its old worker drops it (sampler_worker.hpp)
    std::string& owner = owners[static_cast<size_t>(b)];
    const std::string& now = out[static_cast<size_t>(b)];
    if (owner == now) continue;
    if (Worker* old = roster.find(owner)) {
      old->held.erase(digests[static_cast<size_t>(b)]);
      old->sent.erase(digests[static_cast<size_t>(b)]);
    }
    owner = now;
  }
  return out;
}

}  // namespace hbirl::services
