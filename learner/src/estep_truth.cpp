#include "learner/estep.hpp"

namespace hbirl {

TruthEStep::TruthEStep(const Mdp& mdp, std::vector<Trajectory> trajectories)
    : trajectories_(std::move(trajectories)), counts_(visit_counts(mdp, trajectories_)) {}

EStepResult TruthEStep::expect(const SoftSolution& policy, EStepState& /*state*/) const {
  EStepResult result;
  result.counts = counts_;
  double ll = 0.0;
  for (Eigen::Index r = 0; r < counts_.size(); ++r) {
    if (counts_[r] > 0.0) ll += counts_[r] * policy.log_policy[r];
  }
  result.log_likelihood = ll;
  result.objective = ll;
  return result;
}

std::vector<int> TruthEStep::trajectory_lengths() const {
  std::vector<int> lengths;
  lengths.reserve(trajectories_.size());
  for (const auto& t : trajectories_) lengths.push_back(static_cast<int>(t.size()));
  return lengths;
}

}  // namespace hbirl
