// The observations a problem file is learned from (problem_observations.hpp).
#include "problem/problem_observations.hpp"

#include <string>

#include "learner/controlled_prior.hpp"
#include "learner/input_error.hpp"

namespace hbirl {

ObservationPrior problem_prior(const Problem& problem) {
  if (!problem.observation_model) {
    throw InputError("observation_model", "missing; learning from observations needs it");
  }
  std::vector<ObservedTrajectory> controlled_observed;
  std::vector<Trajectory> controlled_truth;
  for (const DemonstratedTrajectory& item : problem.demonstration) {
    if (!item.controlled) continue;
    controlled_observed.push_back(*item.steps);
    controlled_truth.push_back(*item.truth);
  }
  ObservationPrior prior = *problem.observation_model;
  // A controlled run replaces the stated subject prior, as in the service set (sim_driver/registry/domain.hpp).
  if (!controlled_observed.empty()) {
    prior.subject_alpha = controlled_run_prior(problem.mdp, controlled_truth, controlled_observed, prior.num_symbols);
  }
  return prior;
}

ProblemObservations problem_observations(const Problem& problem) {
  ProblemObservations out;
  out.prior = problem_prior(problem);
  for (size_t i = 0; i < problem.demonstration.size(); ++i) {
    const DemonstratedTrajectory& item = problem.demonstration[i];
    if (item.controlled) continue;  // in the prior
    if (!item.steps) {
      throw InputError("demonstration[" + std::to_string(i) + "].steps",
                       "missing; learning from observations needs it for every trajectory");
    }
    out.trajectories.push_back(*item.steps);
    out.demonstration_index.push_back(i);
  }
  if (out.trajectories.empty()) {
    throw InputError("demonstration",
                     problem.demonstration.empty() ? "has no trajectories" : "has only controlled-run trajectories");
  }
  return out;
}

}  // namespace hbirl
