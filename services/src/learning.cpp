#include "services/learning.hpp"

#include "learner/controlled_prior.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "perception/labeller.hpp"
#include "sim_driver/gridworld.hpp"
#include "sim_driver/onion.hpp"

namespace hbirl::services {

namespace {
[[noreturn]] void unknown_domain(const std::string& domain) {
  throw InputError("domain", "'" + domain + "' is not a domain hbirl's services know (onion, gridworld)");
}
}  // namespace

Mdp domain_mdp(const std::string& domain) {
  if (domain == "onion") return onion::make_onion_mdp();
  if (domain == "gridworld") return make_gridworld();
  unknown_domain(domain);
}

DomainNames domain_names(const std::string& domain, int num_sources) {
  DomainNames n;
  if (domain == "onion") {
    n.states = onion::state_names();
    n.actions = onion::action_names();
    n.features = onion::feature_names();
    for (int r = 0; r < perception::kRegionRows; ++r) {
      for (int c = 0; c < perception::kRegionColumns; ++c) n.symbols.push_back("R" + std::to_string(r + 1) + "C" + std::to_string(c + 1));
    }
    n.symbols.push_back("bright onion");
    n.symbols.push_back("dark onion");
    n.sources = {"subject (expert)", "blue-shirt person", "other onions", "foreground person"};
  } else if (domain == "gridworld") {
    n.states = gridworld_state_names(GridworldOptions{}.size);
    n.actions = gridworld_action_names();
    n.features = gridworld_feature_names();
    for (const auto& f : n.features) n.symbols.push_back("near " + f);
    n.sources = {"subject (expert)"};
  } else {
    unknown_domain(domain);
  }
  for (int e = static_cast<int>(n.sources.size()); e < num_sources; ++e) n.sources.push_back("element " + std::to_string(e));
  return n;
}

Eigen::MatrixXd subject_prior(const std::string& domain, const Mdp& mdp, const std::vector<Trajectory>& truth,
                              const std::vector<ObservedTrajectory>& observed, int num_symbols) {
  if (domain == "onion") {
    if (num_symbols != perception::kNumSymbols) throw InputError("observations.num_symbols", "differs from the domain's");
    return controlled_run_prior(mdp, truth, observed, num_symbols, onion::controlled_prior_options());
  }
  if (domain != "gridworld") unknown_domain(domain);
  return controlled_run_prior(mdp, truth, observed, num_symbols);
}

Learned learn_from_dataset(const Mdp& mdp, const Dataset& data, const LearningOptions& options,
                           std::shared_ptr<const BlockExecutor> executor, ProgressFn progress) {
  if (data.observed.empty()) throw InputError("demonstrations", "none received");
  if (data.controlled_observed.empty()) throw InputError("controlled run", "no controlled episodes: no subject prior");
  ObservationPrior prior;
  prior.num_symbols = data.num_symbols;
  prior.num_confounders = data.num_sources - 1;
  prior.subject_alpha = subject_prior(data.domain, mdp, data.controlled_truth, data.controlled_observed, data.num_symbols);
  prior.confounder_alpha = Eigen::MatrixXd::Ones(prior.num_confounders, prior.num_symbols);
  use_alpha_update(prior, options.update);
  // The bus carries the stated eta only: remote workers cannot compute with learned eta.
  prior.learn_eta = false;
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
    learn.on_iteration = [&progress, &prior](int, int iteration, double ll, const Eigen::VectorXd& theta, const EStepResult&,
                                             const ObservationPrior* alpha) { progress(iteration, ll, theta, alpha ? *alpha : prior); };
  }
  const LearnResult result = learn_reward(mdp, estep, learn);
  Learned out;
  out.theta = result.theta;
  out.log_likelihood = result.log_likelihood;
  out.em_iterations = result.restarts[static_cast<size_t>(result.selected_restart)].em_iterations;
  out.trajectories = static_cast<int>(data.observed.size());
  out.digest = dataset_digest(data.observed);
  if (data.true_weights && data.true_weights->size() == mdp.num_features()) {  // else: no ILE
    out.ile = inverse_learning_error(mdp, *data.true_weights, out.theta).ile;
  }
  return out;
}

}  // namespace hbirl::services
