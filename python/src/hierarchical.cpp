// HierarchicalIRL's C++ side (hierarchical.hpp). The learning mirrors cli/learn_command.cpp
// option for option; tests/python checks the two give the same theta bit for bit.
#include "hierarchical.hpp"

#include <cmath>
#include <map>

#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/observation_support.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl::python {

namespace {

void check(const HierarchicalSettings& s) {
  if (s.engine != "exact" && s.engine != "mcmc") throw InputError("engine", "'" + s.engine + "' is not exact or mcmc");
  if (s.optimizer != "lbfgs" && s.optimizer != "eg") throw InputError("optimizer", "'" + s.optimizer + "' is not lbfgs or eg");
  AlphaUpdate update;
  if (!s.alpha_update.empty() && !parse_alpha_update(s.alpha_update, update)) {
    throw InputError("alpha_update", "'" + s.alpha_update + "' is not posterior or paper");
  }
  if (!s.eta.empty() && s.eta != "stated" && s.eta != "learned") throw InputError("eta", "'" + s.eta + "' is not stated or learned");
  if (!(s.l2 >= 0.0) || !std::isfinite(s.l2)) throw InputError("l2", "must be finite and >= 0");
  // The command line's ranges (hbirl learn --help): a number alone must not claim gigabytes.
  if (s.restarts < 1 || s.restarts > 100000) throw InputError("restarts", "must be in [1, 100000]");
  if (s.max_iterations < 1) throw InputError("max_iterations", "must be at least 1");
  if (!(s.tolerance > 0.0)) throw InputError("tolerance", "must be > 0");
  if (!(s.eg_radius > 0.0)) throw InputError("eg_radius", "must be > 0");
  if (!(s.eg_rate > 0.0)) throw InputError("eg_rate", "must be > 0");
  if (s.max_em_iterations < 1) throw InputError("max_em_iterations", "must be at least 1");
  if (!(s.alpha_tolerance > 0.0)) throw InputError("alpha_tolerance", "must be > 0");
  if (s.max_alpha_iterations < 1) throw InputError("max_alpha_iterations", "must be at least 1");
  if (s.threads < 0 || s.threads > 4096) throw InputError("threads", "must be in [0, 4096] (0: one per core)");
  // The sampler keeps every kept sweep of every chain (4 bytes a step): a million is ~40 MB per chain of 10 steps.
  if (s.mcmc.samples < 1 || s.mcmc.samples > 1000000) throw InputError("mcmc_samples", "must be in [1, 1000000]");
  if (s.mcmc.burn_in < 0 || s.mcmc.burn_in > 1000000) throw InputError("mcmc_burn_in", "must be in [0, 1000000]");
  if (s.mcmc.chains < 1 || s.mcmc.chains > 1000) throw InputError("mcmc_chains", "must be in [1, 1000]");
}

EngineFactory engine_of(const std::string& engine, const McmcOptions& mcmc) {
  return engine == "mcmc" ? mcmc_engine_factory(mcmc) : exact_engine_factory();
}

// hbirl learn's LearnOptions for these settings.
LearnOptions learn_options(const HierarchicalSettings& s) {
  LearnOptions options;
  options.optimizer.kind = s.optimizer == "eg" ? OptimizerKind::kExponentiatedGradient : OptimizerKind::kLbfgs;
  options.optimizer.max_iterations = s.max_iterations;
  options.optimizer.gradient_tolerance = s.tolerance;
  options.optimizer.eg_radius = s.eg_radius;
  options.optimizer.eg_learning_rate = s.eg_rate;
  options.l2 = s.l2;
  options.restarts = s.restarts;
  options.seed = s.seed;
  options.threads = s.threads;
  options.max_em_iterations = s.max_em_iterations;
  options.accelerate = s.engine != "mcmc";  // SQUAREM needs a deterministic E-step
  return options;
}

}  // namespace

void check_prior_fits(const Mdp& mdp, const ObservationPrior& prior) {
  if (prior.subject_alpha.rows() != mdp.num_pairs() || prior.subject_alpha.cols() != prior.num_symbols ||
      prior.confounder_alpha.rows() != prior.num_confounders || prior.confounder_alpha.cols() != prior.num_symbols) {
    throw InputError("prior", "was made for another MDP (" + std::to_string(prior.subject_alpha.rows()) + " state-action pairs, this one " +
                                  std::to_string(mdp.num_pairs()) + ")");
  }
}

FittedHierarchical fit_hierarchical(const Mdp& mdp, std::vector<ObservedTrajectory> observations, ObservationPrior prior,
                                    const HierarchicalSettings& settings) {
  check(settings);
  check_prior_fits(mdp, prior);
  if (observations.empty()) throw InputError("observations", "none given");
  if (settings.learn_observation_model) prior.learn = *settings.learn_observation_model;
  AlphaUpdate update;
  if (!settings.alpha_update.empty() && parse_alpha_update(settings.alpha_update, update)) use_alpha_update(prior, update);
  if (settings.eta == "stated") prior.learn_eta = false;
  if (settings.eta == "learned") prior.learn_eta = true;
  FittedHierarchical fit;
  fit.given = prior;
  fit.engine = settings.engine;
  fit.mcmc_options = settings.mcmc;
  fit.seed = settings.seed;
  fit.contexts_given = std::any_of(observations.begin(), observations.end(), [](const ObservedTrajectory& t) { return !t.contexts.empty(); });
  add_unlisted_source(prior, observations);  // before the check: the catch-all can produce anything
  if (const auto impossible = first_impossible_observation(mdp, observations, prior)) {
    throw InputError("observations[" + std::to_string(impossible->trajectory) + "][" + std::to_string(impossible->step) + "]",
                     (impossible->observation >= 0 ? "observation " + std::to_string(impossible->observation) + ": " : std::string()) +
                         "impossible under the observation model: " + impossible->why);
  }
  ObservationEStepOptions estep_options;
  estep_options.engine = engine_of(settings.engine, settings.mcmc);
  estep_options.alpha_tolerance = settings.alpha_tolerance;
  estep_options.max_alpha_iterations = settings.max_alpha_iterations;
  // Restarts run in parallel; a single restart spreads its E-step over the threads instead.
  estep_options.threads = settings.restarts == 1 ? settings.threads : 1;
  const ObservationEStep estep(mdp, std::move(observations), prior, estep_options);

  LearnOptions options = learn_options(settings);
  struct Iterate {
    double log_likelihood, objective, strength;
    Eigen::VectorXd theta;
  };
  // One list per restart: restarts run on their own threads, each writes only its own.
  std::vector<std::vector<Iterate>> history(static_cast<size_t>(settings.restarts));
  options.on_iteration = [&history](int restart, int, double objective, const Eigen::VectorXd& theta, const EStepResult& e,
                                    const ObservationPrior* alpha) {
    // The subject prior's strength (the posterior update's s) only means something while O is learned that way.
    const double strength = alpha && alpha->learn && alpha->update == AlphaUpdate::kPosterior ? alpha->strength : std::nan("");
    history[static_cast<size_t>(restart)].push_back({e.log_likelihood, objective, strength, theta});
  };
  const LearnResult learned = learn_reward(mdp, estep, options);
  const RestartResult& best = learned.restarts[static_cast<size_t>(learned.selected_restart)];
  fit.theta = learned.theta;
  fit.log_likelihood = learned.log_likelihood;
  fit.em_iterations = best.em_iterations;
  fit.converged = best.converged;
  fit.status = best.optimizer_status;
  for (const Iterate& i : history[static_cast<size_t>(learned.selected_restart)]) {
    fit.history_log_likelihood.push_back(i.log_likelihood);
    fit.history_objective.push_back(i.objective);
    fit.history_prior_strength.push_back(i.strength);
    fit.history_theta.push_back(i.theta);
  }
  fit.refined = best.alpha ? *best.alpha : estep.prior();
  fit.model = dirichlet_mean(fit.refined);
  fit.learned_eta = estep.learned_eta_report(fit.refined);
  if (settings.engine == "mcmc") {
    const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(fit.theta));
    const std::optional<RowMatrix> eta = estep.learned_eta(fit.refined);
    fit.mcmc = estep.statistics(policy, fit.model, settings.seed, eta ? &*eta : nullptr).mcmc;
  }
  return fit;
}

void check_fitted_on(const Mdp& mdp, const FittedHierarchical& fit) {
  if (fit.model.subject.rows() != mdp.num_pairs() || fit.theta.size() != mdp.num_features()) {
    throw InputError("mdp", "is not the MDP this model was fitted on");
  }
}

std::vector<ObservedTrajectory> FittedHierarchical::believed(std::vector<ObservedTrajectory> trajectories) const {
  ObservationPrior prior = given;
  add_unlisted_source(prior, trajectories);
  if (!learned_eta) return trajectories;
  const RowMatrix& learned = learned_eta->learned;
  std::map<std::vector<double>, int> context_of;  // stated eta -> context, when contexts were each distinct eta
  if (!contexts_given) {
    for (Eigen::Index c = 0; c < learned_eta->stated.rows(); ++c) {
      const auto row = learned_eta->stated.row(c);
      context_of.emplace(std::vector<double>(row.data(), row.data() + row.size()), static_cast<int>(c));
    }
  }
  for (ObservedTrajectory& t : trajectories) {
    if (t.eta.cols() != learned.cols()) continue;
    for (int n = 0; n < t.num_observations(); ++n) {
      int c = -1;
      if (contexts_given) {
        c = t.context(n);
      } else {
        const auto it = context_of.find(std::vector<double>(t.eta.row(n).data(), t.eta.row(n).data() + t.eta.cols()));
        if (it != context_of.end()) c = it->second;
      }
      // Only contexts fit saw: an id it never met has a learned eta of no data (uniform).
      if (c >= 0 && c < learned.rows() && learned_eta->observations[c] > 0.0) t.eta.row(n) = learned.row(c);
    }
  }
  return trajectories;
}

Posteriors posteriors(const Mdp& mdp, const FittedHierarchical& fit, const std::vector<ObservedTrajectory>& observations) {
  const std::vector<ObservedTrajectory> seen = fit.believed(observations);
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(fit.theta));
  std::unique_ptr<PosteriorEngine> engine = engine_of(fit.engine, fit.mcmc_options)(mdp);
  const Rng root(fit.seed);
  Posteriors out;
  for (size_t i = 0; i < seen.size(); ++i) {
    Rng rng = root.split(i);
    out.trajectories.push_back(engine->posterior(policy, fit.model, seen[i], rng));
    out.mcmc += out.trajectories.back().mcmc;
  }
  return out;
}

std::vector<double> log_likelihoods(const Mdp& mdp, const FittedHierarchical& fit, const std::vector<ObservedTrajectory>& observations) {
  const std::vector<ObservedTrajectory> seen = fit.believed(observations);
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(fit.theta));
  ExactEngine engine(mdp);
  std::vector<double> out;
  for (const ObservedTrajectory& t : seen) out.push_back(engine.log_likelihood(policy, fit.model, t));
  return out;
}

}  // namespace hbirl::python
