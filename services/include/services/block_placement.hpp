#pragma once
// Which sampler worker computes which block of an E-step pass (estep_service.hpp).
#include <cstdint>
#include <string>
#include <vector>

#include "services/worker_roster.hpp"

namespace hbirl::services {

// Blocks to workers, stably: a block stays with the worker it was given to while that
// worker gets work, so each worker is sent its share of the trajectories once; the blocks
// of workers that left, and those over a worker's even share when others join, go to the
// workers under theirs (even shares: sizes differ by at most one block). Except that while
// some workers have proven themselves (answered before), each one that has not gets one
// block, and no more of them than there are proven ones: heartbeats from processes that
// never answer (a crashed build, a forger) cost a pass one timeout, not the whole pass.
// A block a worker failed to hold twice goes to another (none can: computed here), and a
// worker that failed to hold two and holds none gets nothing -- a block it cannot hold would
// cost every pass it is given in a timeout -- for this data set, or until a minute passes
// without such a failure (Worker::unheld).
//
// `todo`: the blocks to place; `workers`: those that get work; `digests`: every block's;
// `owners`: every block's worker from the passes before (updated). Returns, per block, its
// worker (empty: computed by the optimiser).
std::vector<std::string> place_blocks(const std::vector<int>& todo, std::vector<std::string> workers,
                                      const std::vector<std::uint64_t>& digests, std::vector<std::string>& owners,
                                      WorkerRoster& roster);

}  // namespace hbirl::services
