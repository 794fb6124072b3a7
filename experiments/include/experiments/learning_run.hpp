#pragma once
// One learning run of an experiment: its restarts and EM tolerances as the experiment's
// options say, one thread (an experiment runs its points in parallel, docs/BENCHMARKS.md)
// and a seed of its own from the experiment's seed, the run and the point (confounders,
// demonstrations): the same run gives the same theta whatever else runs beside it.
#include <cstdint>

#include "learner/hidden_data_em.hpp"

namespace hbirl {

template <class ExperimentOptions>
LearnOptions learning_run_options(const ExperimentOptions& o, int run, int point) {
  LearnOptions learn;
  learn.restarts = o.restarts;
  learn.seed = o.seed ^ (static_cast<std::uint64_t>(run) << 20) ^ static_cast<std::uint64_t>(point);
  learn.threads = 1;
  learn.theta_tolerance = o.theta_tolerance;
  learn.likelihood_tolerance = o.likelihood_tolerance;
  return learn;
}

}  // namespace hbirl
