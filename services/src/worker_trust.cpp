#include "services/worker_trust.hpp"

#include <map>

#include "services/estep_wire.hpp"

namespace hbirl::services {

std::vector<int> SpotChecks::choose(const std::vector<int>& todo, const std::vector<std::string>& assigned,
                                    WorkerRoster& roster) {
  std::map<std::string, std::vector<int>> unchecked;  // worker -> its blocks
  for (int b : todo) {
    const std::string& w = assigned[static_cast<size_t>(b)];
    if (!w.empty() && !roster[w].checked) unchecked[w].push_back(b);
  }
  std::vector<int> out;
  for (const auto& [w, blocks] : unchecked) out.push_back(blocks[static_cast<size_t>(rng_() % blocks.size())]);
  if (out.empty() && !todo.empty()) out.push_back(todo[static_cast<size_t>(rng_() % todo.size())]);
  return out;
}

bool SpotChecks::matches(const std::string& worker, const EStepStatistics& answer, const EStepStatistics& here,
                         WorkerRoster& roster) {
  const Worker* w = roster.find(worker);
  const double tolerance = w != nullptr && w->numerics == roster.numerics() ? 0.0 : 1e-9;
  if (!same_statistics(answer, here, tolerance)) return false;
  roster[worker].checked = true;
  return true;
}

}  // namespace hbirl::services
