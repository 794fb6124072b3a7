#pragma once
// Runs fn(i) for every i in [0, n) on up to `threads` threads (0 = one per core).
// Work items must be independent and write only to their own slot, so the outcome does
// not depend on scheduling. If items throw, the exception of the lowest index is
// rethrown after all threads have stopped.
#include <functional>

namespace hbirl {

int default_thread_count();
void parallel_for(int n, int threads, const std::function<void(int)>& fn);

}  // namespace hbirl
