#include "services/learning.hpp"

#include "experiments/onion_data.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "sim_driver/onion.hpp"

namespace hbirl::services {

Mdp domain_mdp(const std::string& domain) {
  if (domain == "onion") return onion::make_onion_mdp();
  throw InputError("domain", "'" + domain + "' is not a domain hbirl's services know (onion)");
}

std::optional<Eigen::VectorXd> domain_true_weights(const std::string& domain) {
  if (domain == "onion") return onion::expert_weights();
  return std::nullopt;
}

Learned learn_from_dataset(const Mdp& mdp, const Dataset& data, const LearningOptions& options,
                           std::shared_ptr<const BlockExecutor> executor, ProgressFn progress) {
  if (data.observed.empty()) throw InputError("demonstrations", "none received");
  if (data.controlled_observed.empty()) throw InputError("controlled run", "no controlled episodes: no subject prior");
  onion::OnionDemonstration controlled;
  controlled.truth = data.controlled_truth;
  controlled.observed = data.controlled_observed;
  for (const auto& t : data.controlled_truth) {
    for (const auto& x : t) {
      if (x.state >= mdp.num_states || x.action >= mdp.num_actions) throw InputError("ground_truth", "state or action outside the domain");
    }
  }
  ObservationPrior prior;
  prior.num_symbols = data.num_symbols;
  prior.num_confounders = data.num_sources - 1;
  prior.subject_alpha = onion::controlled_prior(mdp, controlled);
  if (prior.subject_alpha.cols() != data.num_symbols) throw InputError("observations.num_symbols", "differs from the domain's");
  prior.confounder_alpha = Eigen::MatrixXd::Ones(prior.num_confounders, prior.num_symbols);
  prior.c = options.c;
  ObservationEStepOptions estep_options;
  estep_options.max_alpha_iterations = options.max_alpha_iterations;
  estep_options.alpha_tolerance = options.alpha_tolerance;
  estep_options.executor = std::move(executor);
  const ObservationEStep estep(mdp, data.observed, prior, estep_options);
  LearnOptions learn;
  learn.seed = options.seed;
  learn.threads = 1;  // one E-step at a time on the bus
  learn.theta_tolerance = options.theta_tolerance;
  learn.likelihood_tolerance = options.likelihood_tolerance;
  if (progress) {
    learn.on_iteration = [&progress](int, int iteration, double ll, const Eigen::VectorXd& theta, const EStepResult&) {
      progress(iteration, ll, theta);
    };
  }
  const LearnResult result = learn_reward(mdp, estep, learn);
  Learned out;
  out.theta = result.theta;
  out.log_likelihood = result.log_likelihood;
  out.em_iterations = result.restarts[static_cast<size_t>(result.selected_restart)].em_iterations;
  out.trajectories = static_cast<int>(data.observed.size());
  out.digest = dataset_digest(data.observed);
  if (const auto truth = domain_true_weights(data.domain)) out.ile = inverse_learning_error(mdp, *truth, out.theta).ile;
  return out;
}

}  // namespace hbirl::services
