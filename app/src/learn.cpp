#include "app/learn.hpp"

#include <future>

#include "learner/input_error.hpp"
#include "learner/observation_support.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl::app {

namespace {

// HiddenDataEM's options: the settings', SQUAREM only with a deterministic E-step.
LearnOptions em_options(const LearnSettings& settings) {
  LearnOptions options = settings.em;
  options.accelerate = settings.engine != "mcmc";
  return options;
}

// Every iterate handed to the hook, with the E-step it came from.
IterationReport report_of(const LearnHooks& hooks, const ObservationEStep* observed) {
  if (!hooks.on_iteration) return nullptr;
  return [&hooks, observed](int restart, int iteration, double objective, const Eigen::VectorXd& theta,
                            const EStepResult& e, const ObservationPrior* alpha) {
    hooks.on_iteration(Iterate{restart, iteration, objective, theta, e, alpha, observed});
  };
}

// Every observation must be one some source can make (observation_support.hpp): otherwise
// the data have probability 0 under every reward, and EM would say nothing useful.
void check_possible(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations, const ObservationPrior& prior,
                    const LearnHooks& hooks) {
  const auto impossible = first_impossible_observation(mdp, observations, prior);
  if (!impossible) return;
  std::string where = hooks.trajectory_name ? hooks.trajectory_name(impossible->trajectory)
                                            : "observations[" + std::to_string(impossible->trajectory) + "]";
  where += ".steps[" + std::to_string(impossible->step) + "]";
  if (impossible->observation >= 0) where += ".observations[" + std::to_string(impossible->observation) + "]";
  throw InputError(where, "impossible under the observation model: " + impossible->why);
}

// What the posterior needs, checked before EM rather than after it.
void check_posterior_settings(const LearnSettings& settings) {
  if (settings.posterior.samples == 0) return;
  if (settings.engine != "exact") {
    throw InputError("posterior_samples", "needs the exact engine: the MCMC E-step's likelihood of theta is noisy");
  }
  check_posterior_options(settings.posterior);
}

// The posterior over theta at what EM learned (the selected restart's observation model),
// when the settings ask for draws, and the confidence in the learned policy it gives.
void draw_posterior(const Mdp& mdp, const LearnSettings& settings, Learned& out) {
  if (settings.posterior.samples == 0) return;
  EStepState state = out.estep->initial_state(out.seed);
  if (out.observed != nullptr) state.alpha = out.refined;
  RewardPosteriorOptions options = settings.posterior;
  options.seed = settings.em.seed;
  out.posterior = sample_reward_posterior(mdp, *out.estep, state, out.em.theta, options, settings.em.soft_vi);
  out.confidence = policy_confidence(mdp, *out.posterior, out.em.theta);
}

// The confidence averaged over two models of the sensor with equal weight: O as EM learned
// it, and O held at the prior (the controlled run's; docs/MODEL.md "The posterior over
// theta"). A posterior that holds the learned O cannot see a joint mode of theta and O
// other than EM's; the prior's O is the second opinion that can. Their likelihoods do not
// weigh them (the learned O's is fitted to these data and always higher).
constexpr double kPriorOWeight = 0.5;

// The confidence with O held at the prior: what EM and the posterior give then, asked of
// the policy learned with O learned.
Learned learned_at_prior_o(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations,
                           const LearnSettings& settings, const ObservationPrior& given, int threads) {
  LearnSettings held = settings;
  held.learn_observation_model = false;
  held.em.warm_start.reset();
  held.em.threads = threads;
  return learn(mdp, observations, given, held, {});
}

// The posterior at what EM learned and, when O was learned, the confidence averaged over
// the two models of the sensor. The two are independent: on two threads when the settings
// allow more than one (the same bits either way).
void draw_posteriors(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations, const LearnSettings& settings,
                     Learned& out) {
  if (settings.posterior.samples == 0) return;
  if (!out.given.learn) {
    draw_posterior(mdp, settings, out);
    return;
  }
  std::optional<Learned> at_prior;
  if (settings.em.threads == 1) {
    draw_posterior(mdp, settings, out);
    at_prior = learned_at_prior_o(mdp, observations, settings, out.given, 1);
  } else {
    std::future<Learned> second =
        std::async(std::launch::async, [&] { return learned_at_prior_o(mdp, observations, settings, out.given, 1); });
    draw_posterior(mdp, settings, out);
    at_prior = second.get();
  }
  const PolicyConfidence prior_o = policy_confidence(mdp, *at_prior->posterior, out.em.theta);
  out.confidence_learned_o = out.confidence;
  out.confidence_prior_o = prior_o;
  out.confidence = mix(*out.confidence, prior_o, kPriorOWeight);
  out.posterior_prior_o = std::move(at_prior->posterior);
}

}  // namespace

void check_prior_fits(const Mdp& mdp, const ObservationPrior& prior) {
  if (prior.subject_alpha.rows() != mdp.num_pairs() || prior.subject_alpha.cols() != prior.num_symbols ||
      prior.confounder_alpha.rows() != prior.num_confounders || prior.confounder_alpha.cols() != prior.num_symbols) {
    throw InputError("prior", "was made for another MDP (" + std::to_string(prior.subject_alpha.rows()) +
                                  " state-action pairs, this one " + std::to_string(mdp.num_pairs()) + ")");
  }
  if (prior.num_end_symbols() > 0 && prior.end_alpha.rows() != mdp.num_states) {
    throw InputError("prior", "its end sensor was made for another MDP (" + std::to_string(prior.end_alpha.rows()) +
                                  " states, this one " + std::to_string(mdp.num_states) + ")");
  }
}

EngineFactory engine_factory(const LearnSettings& settings) {
  return settings.engine == "mcmc" ? mcmc_engine_factory(settings.mcmc) : exact_engine_factory();
}

Learned learn(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations, ObservationPrior prior,
              const LearnSettings& settings, const LearnHooks& hooks) {
  check_prior_fits(mdp, prior);
  if (observations.empty()) throw InputError("observations", "none given");
  check_posterior_settings(settings);
  Learned out;
  out.seed = settings.em.seed;
  apply_to_prior(settings, prior);
  out.given = prior;
  // The catch-all for unlisted confounders widens every eta: a copy only then.
  std::optional<std::vector<ObservedTrajectory>> widened;
  if (adds_unlisted_source(prior)) {
    widened = observations;
    add_unlisted_source(prior, *widened);  // before the check: the catch-all can produce anything
  }
  const std::vector<ObservedTrajectory>& seen = widened ? *widened : observations;
  check_possible(mdp, seen, prior, hooks);
  ObservationEStepOptions estep_options;
  estep_options.engine = engine_factory(settings);
  estep_options.alpha_tolerance = settings.alpha_tolerance;
  estep_options.max_alpha_iterations = settings.max_alpha_iterations;
  // Restarts run in parallel; a single restart spreads its E-step over the threads instead.
  estep_options.threads = settings.em.restarts == 1 ? settings.em.threads : 1;
  estep_options.executor = hooks.executor;
  estep_options.watch = hooks.watch;
  auto estep = std::make_unique<ObservationEStep>(mdp, seen, std::move(prior), estep_options);
  widened.reset();  // the E-step holds its own (merged) copy
  out.observed = estep.get();
  out.em = learn_reward(mdp, *estep, em_options(settings), report_of(hooks, out.observed));
  out.refined = out.best().alpha ? *out.best().alpha : estep->prior();
  out.model = dirichlet_mean(out.refined);
  out.learned_eta = estep->learned_eta_report(out.refined);
  out.estep = std::move(estep);
  draw_posteriors(mdp, observations, settings, out);
  return out;
}

Learned learn_from_truth(const Mdp& mdp, std::vector<Trajectory> truth, const LearnSettings& settings,
                         const LearnHooks& hooks) {
  check_posterior_settings(settings);
  Learned out;
  out.seed = settings.em.seed;
  out.estep = std::make_unique<TruthEStep>(mdp, std::move(truth));
  out.em = learn_reward(mdp, *out.estep, em_options(settings), report_of(hooks, nullptr));
  draw_posterior(mdp, settings, out);
  return out;
}

namespace {

// Estimates 1..N, each learned on a prefix by `learn_prefix` and warm-started from the last.
template <typename Data, typename LearnPrefix>
void anytime(const std::vector<Data>& data, const LearnSettings& settings, const EstimateReport& on_estimate,
             const LearnPrefix& learn_prefix) {
  if (data.empty()) throw InputError("observations", "none given");
  LearnSettings step = settings;
  for (size_t n = 1; n <= data.size(); ++n) {
    const std::vector<Data> prefix(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(n));
    const Learned learned = learn_prefix(prefix, step);
    on_estimate(static_cast<int>(n), learned);
    step.em.warm_start = learned.em.theta;
  }
}

}  // namespace

void learn_anytime(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations, const ObservationPrior& prior,
                   const LearnSettings& settings, const LearnHooks& hooks, const EstimateReport& on_estimate) {
  anytime(observations, settings, on_estimate,
          [&](const std::vector<ObservedTrajectory>& first, const LearnSettings& step) {
            return learn(mdp, first, prior, step, hooks);
          });
}

void learn_from_truth_anytime(const Mdp& mdp, const std::vector<Trajectory>& truth, const LearnSettings& settings,
                              const LearnHooks& hooks, const EstimateReport& on_estimate) {
  anytime(truth, settings, on_estimate, [&](const std::vector<Trajectory>& first, const LearnSettings& step) {
    return learn_from_truth(mdp, first, step, hooks);
  });
}

EStepStatistics Learned::final_statistics(const Mdp& mdp) const {
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(em.theta));
  if (observed == nullptr) {
    EStepState state = estep->initial_state(0);
    EStepStatistics out;
    out.counts = estep->expect(policy, state).counts;
    return out;
  }
  const std::optional<RowMatrix> eta = observed->learned_eta(refined);
  return observed->statistics(policy, model, seed, eta ? &*eta : nullptr);
}

nlohmann::ordered_json posterior_summary(const Learned& learned) {
  const RewardPosterior& p = *learned.posterior;
  const auto list = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
  nlohmann::ordered_json j;
  j["confidence"] = learned.confidence->near_optimal;
  j["confidence_means"] =
      "the posterior probability that the learned reward's optimal policy is within 5% of the optimal value "
      "(ILE <= 0.05 ||V*||_1); from observations averaged over the observation model as learned and as the "
      "prior says (confidence_by_sensor_model); its calibration is measured in docs/results/calibration";
  if (learned.confidence_prior_o) {
    j["confidence_by_sensor_model"] = {{"learned", learned.confidence_learned_o->near_optimal},
                                       {"prior", learned.confidence_prior_o->near_optimal}};
  }
  j["probability_optimal"] = learned.confidence->optimal;
  j["expected_ile_relative"] = learned.confidence->expected_relative_ile;
  nlohmann::ordered_json actions = nlohmann::ordered_json::array();
  const Eigen::MatrixXd& optimal = learned.confidence->action_optimal;
  for (Eigen::Index s = 0; s < optimal.rows(); ++s) actions.push_back(list(optimal.row(s).transpose()));
  j["action_optimal"] = actions;
  j["mean"] = list(p.mean());
  const Eigen::VectorXd lo = p.quantile(0.05), hi = p.quantile(0.95);
  nlohmann::ordered_json intervals = nlohmann::ordered_json::array();
  for (Eigen::Index k = 0; k < lo.size(); ++k) intervals.push_back({lo[k], hi[k]});
  j["interval_90"] = intervals;
  j["mode"] = list(p.mode);
  j["prior_scale"] = p.prior_scale;
  j["samples"] = p.samples.rows();
  j["effective_samples"] = p.effective_samples;
  j["evaluations"] = p.evaluations;
  return j;
}

}  // namespace hbirl::app
