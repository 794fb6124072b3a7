#pragma once
// Trusting sampler workers' answers (estep_service.hpp; docs/RELIABILITY.md): each pass the
// optimiser computes some of the blocks it gave the workers and compares the answers.
#include <random>
#include <string>
#include <vector>

#include "learner/estep_observations.hpp"
#include "services/worker_roster.hpp"

namespace hbirl::services {

class SpotChecks {
 public:
  // The blocks checked this pass: one block, at random, of each worker never checked (a
  // worker that always lies is caught before any of its answers is used; it costs one block
  // per worker once), or, once all are, one block at random (a worker that lies now and then
  // is caught in time, never by construction). `assigned`: each block's worker.
  std::vector<int> choose(const std::vector<int>& todo, const std::vector<std::string>& assigned, WorkerRoster& roster);
  // Whether `worker`'s `answer` is the optimiser's own `here`: bit for bit when it computes
  // with the optimiser's numerics, else to a relative 1e-9 (the last bits may differ). A
  // match marks the worker checked.
  bool matches(const std::string& worker, const EStepStatistics& answer, const EStepStatistics& here,
               WorkerRoster& roster);

 private:
  // Unpredictable to the workers (the request's seed is not); it never changes a result (a
  // checked block's bits are the same either way).
  std::mt19937_64 rng_{std::random_device{}()};
};

}  // namespace hbirl::services
