#pragma once
// The E-step interface of HiddenDataEM (SPEC §2). An E-step turns a policy into the
// expected number of visits N_hat(s,a) of each state-action pair under the posterior
// Pr(X | data; theta) -- the sufficient statistic of the M-step (maxcausalent.hpp), from
// which the expected feature counts phi_hat = Phi^T N_hat follow -- and the data's
// log-likelihood under that policy.
//
// Implementations: TruthEStep (known trajectories; the posterior is a point mass).
// Observation-based engines (exact forward-backward, MCMC) implement the same interface.
#include <cstdint>
#include <optional>
#include <vector>

#include "learner/observations.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/trajectory.hpp"

namespace hbirl {

struct EStepResult {
  Eigen::VectorXd counts;       // expected visits per (s, a) pair, summed over trajectories
  double log_likelihood = 0.0;  // log Pr(data | theta)
  int alpha_iterations = 0;     // observation-model refinements made by this call
  bool alpha_converged = true;
  int impossible_trajectories = 0;  // probability 0 under the model: left out
};

// What an E-step carries from one EM iteration to the next: the refined Dirichlet
// parameters, and the random stream of sampling engines.
struct EStepState {
  std::optional<ObservationPrior> alpha;
  std::uint64_t seed = 0;
  std::uint64_t calls = 0;
};

class EStep {
 public:
  virtual ~EStep() = default;
  virtual EStepState initial_state(std::uint64_t seed) const {
    EStepState state;
    state.seed = seed;
    return state;
  }
  // Must be safe to call from several threads at once (with different states).
  virtual EStepResult expect(const SoftSolution& policy, EStepState& state) const = 0;
  // False when the posterior does not depend on the policy (known trajectories): then
  // HiddenDataEM is a single M-step.
  virtual bool depends_on_policy() const = 0;
  // Number of trajectories and their lengths (the horizons of the data).
  virtual std::vector<int> trajectory_lengths() const = 0;
};

// True trajectories: N_hat is the visit count; the log-likelihood is
// sum_t log pi(a_t | s_t) (the transition terms do not depend on theta and are left out).
class TruthEStep final : public EStep {
 public:
  TruthEStep(const Mdp& mdp, std::vector<Trajectory> trajectories);
  EStepResult expect(const SoftSolution& policy, EStepState& state) const override;
  bool depends_on_policy() const override { return false; }
  std::vector<int> trajectory_lengths() const override;
  const std::vector<Trajectory>& trajectories() const { return trajectories_; }

 private:
  std::vector<Trajectory> trajectories_;
  Eigen::VectorXd counts_;
};

}  // namespace hbirl
