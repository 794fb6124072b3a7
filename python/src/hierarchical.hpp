#pragma once
// HierarchicalIRL's C++ side (python/hbirl/__init__.py): HiddenDataEM on observations with
// the observation model and eta learned, as `hbirl learn --problem` runs it -- the same
// E-step, options and defaults, so the same theta bit for bit -- and the fitted model's
// posterior and log-likelihood of any observations.
#include <optional>
#include <string>
#include <vector>

#include "learner/estep_mcmc.hpp"
#include "learner/estep_observations.hpp"
#include "learner/mcmc_diagnostics.hpp"
#include "learner/observation_model.hpp"

namespace hbirl::python {

struct HierarchicalSettings {
  std::string engine = "exact";  // or "mcmc"
  McmcOptions mcmc = [] {
    McmcOptions o;
    o.chains = 4;  // as hbirl learn's --mcmc-chains
    return o;
  }();
  std::optional<bool> learn_observation_model;  // unset: as the prior says
  std::string alpha_update;                     // "posterior" or "paper"; empty: as the prior says
  std::string eta;                              // "stated" or "learned"; empty: as the prior says
  std::string optimizer = "lbfgs";
  double l2 = 0.0;
  int restarts = 1;
  std::uint64_t seed = 1;
  int max_iterations = 1000;
  double tolerance = 1e-9;
  double eg_radius = 50.0;
  double eg_rate = 0.25;
  int max_em_iterations = 300;
  double alpha_tolerance = 1e-4;
  int max_alpha_iterations = 10;
  int threads = 0;
};

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
  std::string engine;
  McmcOptions mcmc_options;
  std::uint64_t seed = 1;

  // The observations as this model sees them: the unlisted catch-all added as when fitting,
  // and with learned eta each observation's eta replaced by its context's learned one
  // (contexts by id when the observations carry them, else by the stated eta; a context
  // fit never saw keeps its stated eta).
  std::vector<ObservedTrajectory> believed(std::vector<ObservedTrajectory> trajectories) const;
};

// InputError("prior") unless the prior's shapes are the MDP's.
void check_prior_fits(const Mdp& mdp, const ObservationPrior& prior);

// Throws InputError naming the argument or the observation when it cannot be learned from.
FittedHierarchical fit_hierarchical(const Mdp& mdp, std::vector<ObservedTrajectory> observations, ObservationPrior prior,
                                    const HierarchicalSettings& settings);

struct Posteriors {
  std::vector<TrajectoryPosterior> trajectories;
  McmcDiagnostics mcmc;  // worst over the trajectories (neutral for the exact engine)
};
// InputError("mdp") unless `fit` was fitted on an MDP of this one's shape.
void check_fitted_on(const Mdp& mdp, const FittedHierarchical& fit);
// Each trajectory's posterior under the fitted theta and model, by the fit's engine (MCMC:
// trajectory i from stream i of the fit's seed, as hbirl posterior).
Posteriors posteriors(const Mdp& mdp, const FittedHierarchical& fit, const std::vector<ObservedTrajectory>& observations);
// log Pr(observations | theta, O), exact (forward pass), per trajectory.
std::vector<double> log_likelihoods(const Mdp& mdp, const FittedHierarchical& fit, const std::vector<ObservedTrajectory>& observations);

}  // namespace hbirl::python
