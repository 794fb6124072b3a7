#pragma once
// Learning the reward from a data set assembled off the bus (dataset.hpp), the same way
// live (hbirl-optimiser, with sampler workers) and offline (hbirl learn --log): the
// partially-controlled model with the labeller's eta, the subject prior from the run's
// controlled episodes, uninformative priors for the confounding elements.
#include <functional>
#include <memory>
#include <optional>

#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "services/dataset.hpp"

namespace hbirl::services {

// The domains the services know: "onion" (paper §Experiments B, from camera frames) and "gridworld"
// (the paper's 5x5 Gridworld; its simulator publishes the observations itself).
// Each throws InputError("domain", ...) for any other name.
Mdp domain_mdp(const std::string& domain);
// The names of a domain's states, actions, reward features, observation symbols and
// sources (the subject, then `num_sources` - 1 confounding elements in all). Onion
// symbols: "R2C3" is the gripper seen in the field of view's region row 2, column 3 (of
// 4 x 5); "bright onion", "dark onion".
struct DomainNames {
  std::vector<std::string> states, actions, features, symbols, sources;
};
DomainNames domain_names(const std::string& domain, int num_sources = 1);
// The informative prior for the subject's observation model from the controlled run's
// observations and true steps (learner/controlled_prior.hpp): onion, the symbol counts
// per visit of (s, a) plus 1 (hbirl experiment onion); gridworld, the symbol counts plus 1
// (hbirl experiment gridworld, paper §Experiments A). Throws InputError for true steps or
// symbols outside the domain.
Eigen::MatrixXd subject_prior(const std::string& domain, const Mdp& mdp, const std::vector<Trajectory>& truth,
                              const std::vector<ObservedTrajectory>& observed, int num_symbols);

struct LearningOptions {
  AlphaUpdate update = AlphaUpdate::kPosterior;  // observation-model refinement (observation_model.hpp)
  double c = 0.5;                   // the paper's step size (update paper only)
  std::uint64_t seed = 1;
  int max_alpha_iterations = 1;     // as in hbirl experiment onion
  double alpha_tolerance = 1e-3;
  double theta_tolerance = 1e-3;
  double likelihood_tolerance = 1e-6;
};

struct Learned {
  Eigen::VectorXd theta;
  double log_likelihood = 0.0;
  std::optional<double> ile;         // when the ground truth gave the expert's true weights
  int em_iterations = 0;
  int trajectories = 0;
  std::uint64_t digest = 0;          // of the demonstrations learned from
};

// Called after every EM iteration: iteration, log-likelihood, theta, and the observation
// model's refined Dirichlet parameters.
using ProgressFn = std::function<void(int, double, const Eigen::VectorXd&, const ObservationPrior&)>;

// Throws InputError when the data set cannot be learned from (no demonstrations, no
// controlled run).
Learned learn_from_dataset(const Mdp& mdp, const Dataset& data, const LearningOptions& options,
                           std::shared_ptr<const BlockExecutor> executor = nullptr, ProgressFn progress = nullptr);

}  // namespace hbirl::services
