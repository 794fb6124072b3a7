#pragma once
// A recorded run of the service set as a problem (docs/services.md "Services and channels"): what
// `hbirl export` writes and Python's read_log returns -- the domain's MDP and names, the
// demonstrations as the live optimiser received them and the observation prior it learned
// from (the controlled run's counts included), so that learning the problem again starts
// where the optimiser started and gives its theta.
#include <cstdint>
#include <memory>
#include <string>

#include "app/learn_settings.hpp"
#include "problem/problem_file.hpp"
#include "services/optimiser.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl::app {

struct RecordedProblem {
  Problem problem;
  std::string domain;                     // the run's domain, by name
  std::vector<std::string> source_names;  // the subject's, then each element's (empty: none given)
  int controlled_episodes = 0;            // in problem.observation_model's subject prior
  std::int64_t missing_frames = 0;        // never received, even when asked for again
  std::int64_t bad_messages = 0;          // refused by a reader (counted, not fatal)
};

// The problem of a recorded run. `given`: the run's domain when it ran on a domain file
// (null: the built-in domain its markers name). `prior`: the settings that override the
// prior (Front::kPrior), as the run's hbirl-optimiser was told. `reader` names the caller
// in what the recording's readers report. Throws InputError for a recording that cannot
// be read (services::collect_from_log) or holds no demonstrations.
RecordedProblem read_recorded_problem(const services::RecordedRun& run, std::shared_ptr<const Domain> given,
                                      const LearnSettings& prior, const std::string& reader);

}  // namespace hbirl::app
