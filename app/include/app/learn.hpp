#pragma once
// learn(): the one way hbirl learns a reward. `hbirl learn`, the Python estimators and the
// optimiser service all call it, so what they learn from the same data and settings is
// the same by construction: the prior as the settings have it, the catch-all source for
// unlisted confounders (docs/MODEL.md), every observation checked possible, the E-step
// (its engine, and where its blocks are computed), HiddenDataEM with the MaxCausalEnt
// M-step (learner/hidden_data_em.hpp), and the learned observation model and eta.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/learn_settings.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/reward_posterior.hpp"

namespace hbirl::app {

// One accepted EM iterate, as a front end shows progress.
struct Iterate {
  int restart = 0;
  int iteration = 0;  // 1, 2, ...
  double objective = 0.0;
  const Eigen::VectorXd& theta;
  const EStepResult& estep;
  const ObservationPrior* refined;   // the observation model's learned parameters; null when O is not learned
  const ObservationEStep* observed;  // the E-step (null when learning from true trajectories)
};

struct LearnHooks {
  // Where the E-step's blocks are computed (null: here): the optimiser's sampler workers.
  std::shared_ptr<BlockExecutor> executor;
  int watch = -1;  // keep this trajectory's posterior from every pass (EStepResult::watched)
  std::function<void(const Iterate&)> on_iteration;
  // How the front end names trajectory i of its data, for an error about it ("observations[i]").
  std::function<std::string(int)> trajectory_name;
};

// Moved, never copied: `observed` points into `estep`, and a moved-from Learned must not be
// used. Iterate (above) holds references: use it inside on_iteration, do not keep it.
struct Learned {
  LearnResult em;                              // theta, the log-likelihood and every restart
  std::unique_ptr<EStep> estep;                // what EM learned with
  const ObservationEStep* observed = nullptr;  // the same, when learned from observations
  // Learned from observations:
  ObservationPrior given;    // the prior with the settings applied, before the catch-all
  ObservationPrior refined;  // the selected restart's learned parameters (else the E-step's prior, catch-all included)
  ObservationModel model;    // their Dirichlet mean
  std::optional<LearnedEta> learned_eta;
  std::uint64_t seed = 1;
  // The posterior over theta and what it says of the learned policy, when the settings ask
  // for draws (posterior_samples).
  std::optional<RewardPosterior> posterior;
  std::optional<PolicyConfidence> confidence;
  // When O was learned: the posterior with O held at the prior instead (the second model of
  // the sensor the confidence averages over, docs/MODEL.md), and what each model alone says.
  std::optional<RewardPosterior> posterior_prior_o;
  std::optional<PolicyConfidence> confidence_learned_o, confidence_prior_o;

  const RestartResult& best() const { return em.restarts[static_cast<size_t>(em.selected_restart)]; }
  // The E-step at the learned theta and model (the policy of theta; learned eta when eta is
  // learned): expected counts and, for MCMC, its convergence diagnostics.
  EStepStatistics final_statistics(const Mdp& mdp) const;
};

// What the posterior over theta says (learned.posterior must be there; docs/MODEL.md "The
// posterior over theta"), as `hbirl learn` prints it under "posterior" and the Python
// estimators' posterior_: "confidence" (the probability that the learned policy is within
// 5% of the optimal value), "probability_optimal", "expected_ile_relative", per state the
// probability that each action is optimal ("action_optimal"), per weight its
// "mean" and 90% credible interval ("interval_90"), the "mode", the "prior_scale", and how
// it was drawn ("samples", "effective_samples", "evaluations").
nlohmann::ordered_json posterior_summary(const Learned& learned);

// InputError("prior") unless the prior's shapes are the MDP's.
void check_prior_fits(const Mdp& mdp, const ObservationPrior& prior);

// The posterior engine the settings name (engine, mcmc_*).
EngineFactory engine_factory(const LearnSettings& settings);

// Throws InputError naming the setting, the prior or the observation (by
// hooks.trajectory_name) when the data cannot be learned from. `mdp` must outlive the result.
Learned learn(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations, ObservationPrior prior,
              const LearnSettings& settings, const LearnHooks& hooks = {});

// MaxCausalEnt IRL on the expert's true steps (`hbirl learn --from truth`, MaxCausalEntIRL):
// HiddenDataEM whose E-step is the truth.
Learned learn_from_truth(const Mdp& mdp, std::vector<Trajectory> truth, const LearnSettings& settings,
                         const LearnHooks& hooks = {});

// Learning while the demonstrations arrive (docs/MODEL.md "Learning while it watches"):
// for n = 1, 2, ..., N, what learn() (learn_from_truth()) gives on the first n
// trajectories, EM started also from estimate n - 1's theta (LearnOptions::warm_start;
// settings.em.warm_start is the first estimate's). So estimate n is exactly one learn() call
// -- any point of the sequence can be reproduced alone, given the one before -- and, by EM's
// selection rule, it is never worse than a start from scratch on the same n.
using EstimateReport = std::function<void(int demonstrations, const Learned&)>;
void learn_anytime(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations, const ObservationPrior& prior,
                   const LearnSettings& settings, const LearnHooks& hooks, const EstimateReport& on_estimate);
void learn_from_truth_anytime(const Mdp& mdp, const std::vector<Trajectory>& truth, const LearnSettings& settings,
                              const LearnHooks& hooks, const EstimateReport& on_estimate);

// Knowing when it has seen enough (docs/MODEL.md "Learning while it watches"): the rule
// holds once `after` estimates in a row have a confidence >= `at`. Fed the estimates in
// order; hbirl-optimiser --stop-at-confidence and the stopping experiment both use it.
class StopRule {
 public:
  static constexpr int kDefaultAfter = 3;  // k unless told (--stop-after)
  StopRule(double at, int after) : at_(at), after_(after) {}
  // Whether the rule holds with this estimate's confidence (and stays holding while they
  // stay >= at).
  bool holds_with(double confidence) {
    streak_ = confidence >= at_ ? streak_ + 1 : 0;
    return streak_ >= after_;
  }
  int streak() const { return streak_; }

 private:
  double at_;
  int after_;
  int streak_ = 0;
};

}  // namespace hbirl::app
