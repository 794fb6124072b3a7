#pragma once
// A problem file's demonstration as a run a simulator publishes (hbirl publish): the
// observations a lab already has, streamed onto the bus exactly as a sensor would.
#include <memory>

#include "problem/problem_file.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl {

// One frame per step; the controlled-run trajectories ("controlled": true) first, then the
// demonstrations, each in the file's order; true steps (GROUND_TRUTH) for the controlled
// run only. Throws InputError when the file has no observation model or a trajectory
// has no observed steps.
std::unique_ptr<Simulation> recorded_run(const Problem& problem);

}  // namespace hbirl
