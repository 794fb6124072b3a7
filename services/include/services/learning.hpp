#pragma once
// Learning the reward from a data set assembled off the bus (dataset.hpp), the same way
// live (hbirl-optimiser, with sampler workers) and offline (hbirl learn --log): the
// partially-controlled model with the sensor's eta; the observation model the domain
// states (a domain file's), else uninformative priors for the confounding elements; the
// subject prior from the run's controlled episodes when there are any (domain.hpp).
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/learn_settings.hpp"
#include "app/output.hpp"
#include "learner/estep_observations.hpp"
#include "services/dataset.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl::services {

struct Learned {
  Eigen::VectorXd theta;
  double log_likelihood = 0.0;
  std::optional<double> ile;  // when the ground truth gave the expert's true weights
  int em_iterations = 0;
  int trajectories = 0;
  std::uint64_t digest = 0;             // of the demonstrations learned from
  std::optional<LearnedEta> eta;        // when eta was learned
  Eigen::MatrixXd end_sensor;           // the learned O_end, one row per state (empty: no end sensor)
  std::vector<app::PolicyStep> policy;  // the learned reward's, as results show it (app/output.hpp)
  // When posterior draws were asked for (settings.posterior.samples): the posterior
  // probability that the learned policy is within 5% of the optimal value (app::learn).
  std::optional<double> confidence;
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

// The observation prior learned from, before the settings override it (app::apply_to_prior):
// the domain's stated observation model, else uninformative priors for the confounding
// elements; the subject prior from the run's controlled episodes when there are any.
// Throws InputError when the data do not fit the domain (symbols, sources) or there is no
// subject prior.
ObservationPrior observation_prior(const Domain& domain, const Dataset& data);

// Throws InputError when the data set cannot be learned from (no demonstrations, no
// subject prior, symbols outside the domain, an observation no source can make under the
// domain's observation model: "episode[N].steps[t]...", as `hbirl learn` refuses it).
// Learned as `hbirl learn` learns (app::learn) with these settings, the same data and
// prior: so a run learned live and the same data learned offline give the same theta. One
// E-step at a time on the bus, restarts in parallel when computed here (the same bits
// whatever the thread count); the workers get each pass's
// learned eta with the request (estep_service.hpp).
Learned learn_from_dataset(const Domain& domain, const Dataset& data, const app::LearnSettings& settings,
                           std::shared_ptr<BlockExecutor> executor = nullptr, ProgressFn progress = nullptr);

}  // namespace hbirl::services
