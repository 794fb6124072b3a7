#pragma once
// Learning the reward from a data set assembled off the bus (dataset.hpp), the same way
// live (hbirl-optimiser, with sampler workers) and offline (hbirl learn --log): the
// partially-controlled model with the sensor's eta, the subject prior the domain gives
// (from the run's controlled episodes), uninformative priors for the confounding elements.
#include <functional>
#include <memory>
#include <optional>

#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "services/dataset.hpp"
#include "sim_driver/domain.hpp"

namespace hbirl::services {

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

// The expert's true weights, for the ILE: the ground truth's, else the domain's; none when
// they do not fit the domain's features.
std::optional<Eigen::VectorXd> true_weights_of(const Domain& domain, const Dataset& data);

// Throws InputError when the data set cannot be learned from (no demonstrations, no
// subject prior, symbols outside the domain).
Learned learn_from_dataset(const Domain& domain, const Dataset& data, const LearningOptions& options,
                           std::shared_ptr<const BlockExecutor> executor = nullptr, ProgressFn progress = nullptr);

}  // namespace hbirl::services
