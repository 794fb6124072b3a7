#pragma once
// HierarchicalIRL's C++ side (python/hbirl/__init__.py): app::learn with the estimator's
// settings, as `hbirl learn --problem` calls it -- so the same theta bit for bit -- and the
// fitted model's posterior and log-likelihood of any observations.
#include <optional>
#include <string>
#include <vector>

#include "app/learn_settings.hpp"
#include "learner/estep_mcmc.hpp"
#include "learner/estep_observations.hpp"
#include "learner/mcmc_diagnostics.hpp"
#include "learner/observation_model.hpp"

namespace hbirl::python {

// A fitted model: theta, the observation model and eta it learned, and how EM got there.
struct FittedHierarchical {
  Eigen::VectorXd theta;
  double log_likelihood = 0.0;
  int em_iterations = 0;
  bool converged = false;
  std::string status;
  // Per EM iterate of the selected restart; the prior strength is NaN unless O is learned by the posterior update.
  std::vector<double> history_log_likelihood, history_objective, history_prior_strength;
  std::vector<Eigen::VectorXd> history_theta;
  ObservationPrior given;    // the prior learned from, with the settings applied, before the unlisted catch-all
  ObservationPrior refined;  // the learned Dirichlet parameters (the catch-all included)
  ObservationModel model;    // their mean
  std::optional<LearnedEta> learned_eta;
  bool contexts_given = false;  // the observations carried contexts (else each distinct eta was one)
  std::optional<McmcDiagnostics> mcmc;
  std::string posterior;        // app::posterior_summary as JSON text; empty unless posterior_samples asked for it
  app::LearnSettings settings;  // fitted with

  // The observations as this model sees them: the unlisted catch-all added as when fitting,
  // and with learned eta each observation's eta replaced by its context's learned one
  // (contexts by id when the observations carry them, else by the stated eta; a context
  // fit never saw keeps its stated eta).
  std::vector<ObservedTrajectory> believed(std::vector<ObservedTrajectory> trajectories) const;
};

// Throws InputError naming the setting, the prior or the observation when it cannot be learned from.
FittedHierarchical fit_hierarchical(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations,
                                    const ObservationPrior& prior, const app::LearnSettings& settings);

struct Posteriors {
  std::vector<TrajectoryPosterior> trajectories;
  McmcDiagnostics mcmc;  // worst over the trajectories (neutral for the exact engine)
};
// InputError("mdp") unless `fit` was fitted on an MDP of this one's shape.
void check_fitted_on(const Mdp& mdp, const FittedHierarchical& fit);
// Each trajectory's posterior under the fitted theta and model, by the fit's engine (MCMC:
// trajectory i from stream i of the fit's seed, as hbirl posterior).
Posteriors posteriors(const Mdp& mdp, const FittedHierarchical& fit,
                      const std::vector<ObservedTrajectory>& observations);
// log Pr(observations | theta, O), exact (forward pass), per trajectory.
std::vector<double> log_likelihoods(const Mdp& mdp, const FittedHierarchical& fit,
                                    const std::vector<ObservedTrajectory>& observations);

}  // namespace hbirl::python
