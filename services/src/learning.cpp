#include "services/learning.hpp"

#include "app/learn.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl::services {

std::optional<Eigen::VectorXd> true_weights_of(const Domain& domain, const Dataset& data) {
  std::optional<Eigen::VectorXd> w = data.true_weights ? data.true_weights : domain.true_weights();
  if (w && w->size() != domain.mdp().num_features()) return std::nullopt;
  return w;
}

ObservationPrior observation_prior(const Domain& domain, const Dataset& data) {
  if (domain.num_symbols() > 0 && data.num_symbols != domain.num_symbols()) {
    throw InputError("observations.num_symbols", std::to_string(data.num_symbols) + " differs from the domain's " +
                                                     std::to_string(domain.num_symbols()));
  }
  const std::optional<ObservationPrior> stated = domain.stated_prior();
  ObservationPrior prior;
  if (stated) {
    prior = *stated;
    if (data.num_sources != 1 + prior.num_confounders) {
      throw InputError("observations.num_sources", std::to_string(data.num_sources) + " differs from the domain's " +
                                                       std::to_string(1 + prior.num_confounders));
    }
  } else {
    prior.num_symbols = data.num_symbols;
    prior.num_confounders = data.num_sources - 1;
    prior.confounder_alpha = Eigen::MatrixXd::Ones(prior.num_confounders, prior.num_symbols);
  }
  if (!stated || !data.controlled_observed.empty()) {
    prior.subject_alpha = domain.subject_prior(data.controlled_truth, data.controlled_observed, data.num_symbols);
  }
  return prior;
}

Learned learn_from_dataset(const Domain& domain, const Dataset& data, const app::LearnSettings& settings,
                           std::shared_ptr<BlockExecutor> executor, ProgressFn progress) {
  const Mdp& mdp = domain.mdp();
  if (data.observed.empty()) throw InputError("demonstrations", "none received");
  app::LearnSettings one_at_a_time = settings;
  // One E-step at a time on the bus; computed here, restarts (the live estimates' warm
  // start) in parallel. The same bits whatever the thread count (hidden_data_em.hpp).
  if (executor) one_at_a_time.em.threads = 1;
  app::LearnHooks hooks;
  hooks.executor = std::move(executor);
  // An observation impossible under the domain's observation model names its episode.
  hooks.trajectory_name = [&data](int i) {
    return "episode[" + std::to_string(data.episodes[static_cast<size_t>(i)]) + "]";
  };
  if (progress) {
    hooks.watch = static_cast<int>(data.observed.size()) - 1;  // the newest demonstration, for display
    hooks.on_iteration = [&progress](const app::Iterate& i) {
      const ObservationPrior& now = i.refined ? *i.refined : i.observed->prior();
      const std::optional<LearnedEta> eta = i.observed->learned_eta_report(now);
      progress(i.iteration, i.objective, i.theta, now, i.estep, eta ? &*eta : nullptr);
    };
  }
  const app::Learned learned = app::learn(mdp, data.observed, observation_prior(domain, data), one_at_a_time, hooks);
  const LearnResult& result = learned.em;
  Learned out;
  out.theta = result.theta;
  out.log_likelihood = result.log_likelihood;
  out.em_iterations = learned.best().em_iterations;
  out.eta = learned.learned_eta;
  out.end_sensor = learned.model.end;
  if (learned.confidence) out.confidence = learned.confidence->near_optimal;
  out.trajectories = static_cast<int>(data.observed.size());
  out.digest = dataset_digest(data.observed);
  // The learned reward planned once, for the ILE and the policy results show.
  const OptimalPolicy planned = value_iteration(mdp, mdp.reward(out.theta));
  out.policy = app::learned_policy(mdp, planned, soft_value_iteration(mdp, mdp.reward(out.theta)).policy);
  if (const auto truth = true_weights_of(domain, data)) {
    const Eigen::VectorXd true_reward = mdp.reward(*truth);
    out.ile = inverse_learning_error(mdp, true_reward, value_iteration(mdp, true_reward), planned).ile;
  }
  return out;
}

}  // namespace hbirl::services
