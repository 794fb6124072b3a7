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

// The MDP of a domain by name ("onion"); throws InputError("domain", ...) otherwise.
Mdp domain_mdp(const std::string& domain);
// The true reward weights of a simulated domain's expert, when known.
std::optional<Eigen::VectorXd> domain_true_weights(const std::string& domain);

struct LearningOptions {
  double c = 0.5;                   // alpha refinement rate
  std::uint64_t seed = 1;
  int max_alpha_iterations = 1;     // as in hbirl experiment onion
  double alpha_tolerance = 1e-3;
  double theta_tolerance = 1e-3;
  double likelihood_tolerance = 1e-6;
};

struct Learned {
  Eigen::VectorXd theta;
  double log_likelihood = 0.0;
  std::optional<double> ile;         // when the domain's true reward is known
  int em_iterations = 0;
  int trajectories = 0;
  std::uint64_t digest = 0;          // of the demonstrations learned from
};

// Called after every EM iteration: iteration, log-likelihood, theta.
using ProgressFn = std::function<void(int, double, const Eigen::VectorXd&)>;

// Throws InputError when the data set cannot be learned from (no demonstrations, no
// controlled run).
Learned learn_from_dataset(const Mdp& mdp, const Dataset& data, const LearningOptions& options,
                           std::shared_ptr<const BlockExecutor> executor = nullptr, ProgressFn progress = nullptr);

}  // namespace hbirl::services
