#pragma once
// Running an experiment's learning runs over its data sets in parallel: one home for the
// loop the random-task, calibration and stopping experiments share.
#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "experiments/summary.hpp"
#include "learner/parallel.hpp"

namespace hbirl {

// A data set's name in an experiment's runs: the task's seed and which of its data sets.
struct DataSetId {
  std::uint64_t seed = 0;
  int draw = 0;
};

// `variants` runs on each data set, the data sets in parallel: runs[(i * variants) + v] is
// data set ids[i]'s run v, its seed and draw set and learned by `learn(task, v, run)` with
// task = make(ids[i]) (record_run: timed, an error kept). A data set that cannot be made
// fails its runs, not the others'.
template <class Run, class Make, class Learn>
std::vector<Run> on_data_sets(const std::vector<DataSetId>& ids, size_t variants, int threads,
                              const std::function<void(int, int)>& progress, const Make& make, const Learn& learn) {
  std::vector<Run> runs(ids.size() * variants);
  std::atomic<int> done{0};
  const int total = static_cast<int>(runs.size());
  parallel_for(static_cast<int>(ids.size()), threads, [&](int i) {
    const DataSetId& id = ids[static_cast<size_t>(i)];
    std::optional<decltype(make(id))> task;
    std::string task_error;
    try {
      task.emplace(make(id));
    } catch (const std::exception& e) {
      task_error = e.what();
    }
    for (size_t v = 0; v < variants; ++v) {
      Run& r = runs[static_cast<size_t>(i) * variants + v];
      r.seed = id.seed;
      r.draw = id.draw;
      record_run(r, [&](Run& run) {
        if (!task) throw std::runtime_error("no task: " + task_error);
        learn(*task, v, run);
      });
      const int finished = ++done;
      if (progress) progress(finished, total);
    }
  });
  return runs;
}

}  // namespace hbirl
