#include "services/learning.hpp"

#include "learner/input_error.hpp"
#include "learner/metrics.hpp"

namespace hbirl::services {

std::optional<Eigen::VectorXd> true_weights_of(const Domain& domain, const Dataset& data) {
  std::optional<Eigen::VectorXd> w = data.true_weights ? data.true_weights : domain.true_weights();
  if (w && w->size() != domain.mdp().num_features()) return std::nullopt;
  return w;
}

ObservationPrior observation_prior(const Domain& domain, const Dataset& data, const LearningOptions& options) {
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
  if (options.update) use_alpha_update(prior, *options.update);
  if (options.c) prior.c = *options.c;
  if (options.learn_eta) prior.learn_eta = *options.learn_eta;
  return prior;
}

LearningInput learning_input(const Domain& domain, const Dataset& data, const LearningOptions& options) {
  if (data.observed.empty()) throw InputError("demonstrations", "none received");
  LearningInput in{observation_prior(domain, data, options), &data.observed, std::nullopt};
  if (adds_unlisted_source(in.prior)) {
    in.widened = data.observed;
    add_unlisted_source(in.prior, *in.widened);
  }
  return in;
}

Learned learn_from_dataset(const Domain& domain, const Dataset& data, const LearningOptions& options,
                           std::shared_ptr<const BlockExecutor> executor, ProgressFn progress) {
  const Mdp& mdp = domain.mdp();
  LearningInput in = learning_input(domain, data, options);
  const ObservationPrior& prior = in.prior;
  ObservationEStepOptions estep_options;
  estep_options.executor = std::move(executor);
  if (progress) estep_options.watch = static_cast<int>(data.observed.size()) - 1;  // the newest demonstration, for display
  const ObservationEStep estep(mdp, in.observed(), prior, estep_options);
  in.widened.reset();  // the E-step holds its own (merged) copy
  LearnOptions learn;
  learn.seed = options.seed;
  learn.threads = 1;  // one E-step at a time on the bus (the same bits whatever the thread count)
  if (progress) {
    learn.on_iteration = [&progress, &prior, &estep](int, int iteration, double ll, const Eigen::VectorXd& theta,
                                                     const EStepResult& e, const ObservationPrior* alpha) {
      const ObservationPrior& now = alpha ? *alpha : prior;
      const std::optional<LearnedEta> eta = estep.learned_eta_report(now);
      progress(iteration, ll, theta, now, e, eta ? &*eta : nullptr);
    };
  }
  const LearnResult result = learn_reward(mdp, estep, learn);
  Learned out;
  out.theta = result.theta;
  out.log_likelihood = result.log_likelihood;
  const RestartResult& best = result.restarts[static_cast<size_t>(result.selected_restart)];
  out.em_iterations = best.em_iterations;
  out.eta = estep.learned_eta_report(best.alpha ? *best.alpha : prior);
  out.trajectories = static_cast<int>(data.observed.size());
  out.digest = dataset_digest(data.observed);
  if (const auto truth = true_weights_of(domain, data)) out.ile = inverse_learning_error(mdp, *truth, out.theta).ile;
  return out;
}

}  // namespace hbirl::services
