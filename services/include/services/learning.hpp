#pragma once
// Learning the reward from a data set assembled off the bus (dataset.hpp), the same way
// live (hbirl-optimiser, with sampler workers) and offline (hbirl learn --log): the
// partially-controlled model with the sensor's eta; the observation model the domain
// states (a domain file's), else uninformative priors for the confounding elements; the
// subject prior from the run's controlled episodes when there are any (domain.hpp).
#include <functional>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "services/dataset.hpp"
#include "sim_driver/domain.hpp"

namespace hbirl::services {

// How the optimiser learns: as `hbirl learn` does with the same problem (HiddenDataEM's
// and the E-step's defaults; the domain's stated observation model when it has one), so
// a run learned live and the same data learned offline give the same theta. Eta is
// learned per context (the sensor's, else each distinct eta) as `hbirl learn` learns it;
// the workers get each pass's learned eta with the request (estep_service.hpp).
struct LearningOptions {
  std::optional<AlphaUpdate> update;  // overrides the domain's (default: the posterior update)
  std::optional<double> c;            // the paper's step size, overriding the domain's
  std::optional<bool> learn_eta;      // overrides the domain's (default: learned with the posterior update)
  std::uint64_t seed = 1;
};

struct Learned {
  Eigen::VectorXd theta;
  double log_likelihood = 0.0;
  std::optional<double> ile;         // when the ground truth gave the expert's true weights
  int em_iterations = 0;
  int trajectories = 0;
  std::uint64_t digest = 0;          // of the demonstrations learned from
  std::optional<LearnedEta> eta;     // when eta was learned
};

// Called after every EM iteration: iteration, log-likelihood, theta, the observation
// model's refined Dirichlet parameters, the E-step's result, whose `watched` is the
// newest demonstration's posterior from the E-step's last pass, and learned eta (null
// when eta is taken as stated).
using ProgressFn = std::function<void(int, double, const Eigen::VectorXd&, const ObservationPrior&, const EStepResult&,
                                      const LearnedEta*)>;

// The expert's true weights, for the ILE: the ground truth's, else the domain's; none when
// they do not fit the domain's features.
std::optional<Eigen::VectorXd> true_weights_of(const Domain& domain, const Dataset& data);

// The observation prior learned from: see LearningOptions. Throws InputError when the data
// do not fit the domain (symbols, sources) or there is no subject prior.
ObservationPrior observation_prior(const Domain& domain, const Dataset& data, const LearningOptions& options);

// What is learned from: the observation prior above and the demonstrations, with the
// catch-all source for unlisted confounders added to both when the domain's
// observation_model asks for one (add_unlisted_source). The optimiser sends the workers
// these demonstrations, so that both sides hold the data the E-step computes on. They
// are the data set's own unless the catch-all widens their eta: only then is there a copy.
struct LearningInput {
  ObservationPrior prior;
  const std::vector<ObservedTrajectory>* given = nullptr;  // the data set's (it outlives this)
  std::optional<std::vector<ObservedTrajectory>> widened;  // with the catch-all's share of eta
  const std::vector<ObservedTrajectory>& observed() const { return widened ? *widened : *given; }
};
LearningInput learning_input(const Domain& domain, const Dataset& data, const LearningOptions& options);

// Throws InputError when the data set cannot be learned from (no demonstrations, no
// subject prior, symbols outside the domain).
Learned learn_from_dataset(const Domain& domain, const Dataset& data, const LearningOptions& options,
                           std::shared_ptr<const BlockExecutor> executor = nullptr, ProgressFn progress = nullptr);

}  // namespace hbirl::services
