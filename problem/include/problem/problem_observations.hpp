#pragma once
// What `hbirl learn` (and Python's Problem.observations / observation_prior) learns from in
// a problem file (docs/files.md "Problem files"): the demonstrations' observations, the
// controlled run's left out, and the stated observation model with the controlled run's
// symbol counts as the subject prior when the file has one (paper §Experiments: the
// prior comes from watching the subject alone).
#include <cstddef>
#include <vector>

#include "learner/observations.hpp"
#include "problem/problem_file.hpp"

namespace hbirl {

struct ProblemObservations {
  std::vector<ObservedTrajectory> trajectories;  // in file order
  std::vector<std::size_t> demonstration_index;  // each one's index in the file's demonstration
  ObservationPrior prior;
};

// Throws InputError naming the field ("observation_model", "demonstration[i].steps", or
// the controlled run's) when the file cannot be learned from its observations.
ProblemObservations problem_observations(const Problem& problem);
// The prior alone (a file without demonstrations, e.g. a domain file, has one too).
ObservationPrior problem_prior(const Problem& problem);

}  // namespace hbirl
