// HierarchicalIRL's C++ side (hierarchical.hpp): app::learn, as `hbirl learn` calls it;
// tests/python checks the two give the same theta bit for bit.
#include "hierarchical.hpp"

#include <cmath>
#include <map>

#include "app/learn.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/observation_support.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl::python {

FittedHierarchical fit_hierarchical(const Mdp& mdp, const std::vector<ObservedTrajectory>& observations,
                                    const ObservationPrior& prior, const app::LearnSettings& settings) {
  FittedHierarchical fit;
  fit.settings = settings;
  fit.contexts_given = std::any_of(observations.begin(), observations.end(),
                                   [](const ObservedTrajectory& t) { return !t.contexts.empty(); });
  struct Iterate {
    double log_likelihood, objective, strength;
    Eigen::VectorXd theta;
  };
  // One list per restart: restarts run on their own threads, each writes only its own.
  std::vector<std::vector<Iterate>> history(static_cast<size_t>(settings.em.restarts));
  app::LearnHooks hooks;
  hooks.on_iteration = [&history](const app::Iterate& i) {
    // The subject prior's strength (the posterior update's s) only means something while O is learned that way.
    const ObservationPrior* alpha = i.refined;
    const double strength =
        alpha && alpha->learn && alpha->update == AlphaUpdate::kPosterior ? alpha->strength : std::nan("");
    history[static_cast<size_t>(i.restart)].push_back({i.estep.log_likelihood, i.objective, strength, i.theta});
  };
  const app::Learned learned = app::learn(mdp, observations, prior, settings, hooks);
  const RestartResult& best = learned.best();
  fit.given = learned.given;
  fit.theta = learned.em.theta;
  fit.log_likelihood = learned.em.log_likelihood;
  fit.em_iterations = best.em_iterations;
  fit.converged = best.converged;
  fit.status = best.optimizer_status;
  for (const Iterate& i : history[static_cast<size_t>(learned.em.selected_restart)]) {
    fit.history_log_likelihood.push_back(i.log_likelihood);
    fit.history_objective.push_back(i.objective);
    fit.history_prior_strength.push_back(i.strength);
    fit.history_theta.push_back(i.theta);
  }
  fit.refined = learned.refined;
  fit.model = learned.model;
  fit.learned_eta = learned.learned_eta;
  if (settings.engine == "mcmc") fit.mcmc = learned.final_statistics(mdp).mcmc;
  if (learned.posterior) fit.posterior = app::posterior_summary(learned).dump();
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

Posteriors posteriors(const Mdp& mdp, const FittedHierarchical& fit,
                      const std::vector<ObservedTrajectory>& observations) {
  const std::vector<ObservedTrajectory> seen = fit.believed(observations);
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(fit.theta));
  std::unique_ptr<PosteriorEngine> engine = app::engine_factory(fit.settings)(mdp);
  const Rng root(fit.settings.em.seed);
  Posteriors out;
  for (size_t i = 0; i < seen.size(); ++i) {
    Rng rng = root.split(i);
    out.trajectories.push_back(engine->posterior(policy, fit.model, seen[i], rng));
    out.mcmc += out.trajectories.back().mcmc;
  }
  return out;
}

std::vector<double> log_likelihoods(const Mdp& mdp, const FittedHierarchical& fit,
                                    const std::vector<ObservedTrajectory>& observations) {
  const std::vector<ObservedTrajectory> seen = fit.believed(observations);
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(fit.theta));
  ExactEngine engine(mdp);
  std::vector<double> out;
  for (const ObservedTrajectory& t : seen) out.push_back(engine.log_likelihood(policy, fit.model, t));
  return out;
}

}  // namespace hbirl::python
