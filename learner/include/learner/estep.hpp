#pragma once
// The E-step interface of HiddenDataEM (paper §II-A, Algorithm 1). An E-step turns a policy into the
// expected number of visits N_hat(s,a) of each state-action pair under the posterior
// Pr(X | data; theta) -- the sufficient statistic of the M-step (maxcausalent.hpp), from
// which the expected feature counts phi_hat = Phi^T N_hat follow -- and the data's
// log-likelihood under that policy.
//
// Implementations: TruthEStep (known trajectories; the posterior is a point mass) and
// ObservationEStep (estep_observations.hpp: observations with their eta, each
// trajectory's posterior by a PosteriorEngine, exact or MCMC, estep_exact.hpp).
#include <cstdint>
#include <optional>
#include <vector>

#include "learner/mcmc_diagnostics.hpp"
#include "learner/observations.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/trajectory.hpp"

namespace hbirl {

struct EStepResult {
  Eigen::VectorXd counts;       // expected visits per (s, a) pair, summed over trajectories
  double log_likelihood = 0.0;  // log Pr(data | theta, O), at the input point
  // What EM maximises, at the input point: log_likelihood, plus with the posterior
  // observation-model update the prior's term (observation_model.hpp, log_prior_term).
  double objective = 0.0;
  int alpha_iterations = 0;  // observation-model refinements made by this call
  bool alpha_converged = true;
  int impossible_trajectories = 0;  // probability 0 under the model: left out
  // The watched trajectory's posterior from the E-step's last pass (observation E-steps
  // with a watch, estep_observations.hpp): (s, a) marginals per step, empty when none.
  RowMatrix watched;
  double watched_log_likelihood = 0.0;
  // The MCMC engine's worst convergence diagnostics in the E-step's last pass
  // (mcmc_diagnostics.hpp); neutral (nothing checked) for the other engines.
  McmcDiagnostics mcmc;
};

// What an E-step carries from one EM iteration to the next: the refined Dirichlet
// parameters, and the random stream of sampling engines.
struct EStepState {
  std::optional<ObservationPrior> alpha;
  std::uint64_t seed = 0;
  std::uint64_t calls = 0;
};

// A hyper-parameter chosen from the data where EM has converged: the posterior update's
// prior strength, by the held-out log-likelihood of each trajectory left out in turn.
struct StrengthChoice {
  double current_score = 0.0;  // held-out log-likelihood at the current strength
  double best_strength = 1.0;  // the grid's best (the current one on ties)
  double best_score = 0.0;
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
  // The posterior's expected visits and log Pr(data | theta, O) at this policy, with O the
  // mean of the state's observation model held fixed (no refinement): the likelihood of
  // theta alone, and what its gradient is made of (reward_posterior.hpp).
  virtual EStepResult fixed_model_statistics(const SoftSolution& policy, const EStepState& state) const {
    EStepState copy = state;
    return expect(policy, copy);
  }
  // Its log-likelihood at a point EM returned: what a user compares between models.
  double data_log_likelihood(const SoftSolution& policy, const EStepState& state) const {
    return fixed_model_statistics(policy, state).log_likelihood;
  }
  // Nothing when the E-step has no hyper-parameter to choose at this state.
  virtual std::optional<StrengthChoice> choose_strength(const SoftSolution&, const EStepState&) const {
    return std::nullopt;
  }
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
