#include "experiments/gridworld_experiment.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <sstream>

#include "experiments/gridworld_scenario.hpp"
#include "experiments/learning_run.hpp"
#include "experiments/summary.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/metrics.hpp"
#include "learner/parallel.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace hbirl {

namespace {

using Scenario = GridworldScenario;

Scenario make_scenario(const GridworldExperimentOptions& o, int run, int confounders) {
  return make_gridworld_scenario({o.seed, o.size, o.trajectories, o.length, o.per_step}, run, confounders);
}

}  // namespace

GridworldMethodData gridworld_method_data(const GridworldScenario& s, GridworldMethod method, std::uint64_t seed,
                                          int run, int confounders) {
  GridworldMethodData out{s.observations, {}};
  ObservationPrior& prior = out.prior;
  prior.num_symbols = 4;
  prior.learn = true;
  prior.subject_alpha = s.controlled_alpha;
  Rng eta_rng = Rng(seed).split(static_cast<std::uint64_t>(run)).split(2000 + static_cast<std::uint64_t>(confounders));
  switch (method) {
    case GridworldMethod::kTrueObservationFunction:
      prior.num_confounders = confounders;
      prior.subject_alpha = s.subject_o;  // its Dirichlet mean is the true O
      prior.confounder_alpha = s.confounder_o;
      prior.learn = false;
      assign_eta(out.observations, 1 + confounders, EtaKind::kUniform, eta_rng);
      break;
    case GridworldMethod::kUniformEta:
    case GridworldMethod::kPlausibleEta:
      prior.num_confounders = confounders;
      prior.confounder_alpha = Eigen::MatrixXd::Ones(confounders, 4);
      assign_eta(out.observations, 1 + confounders,
                 method == GridworldMethod::kUniformEta ? EtaKind::kUniform : EtaKind::kPlausible, eta_rng);
      break;
    default:  // Ignore CE (and True Trajectories, which reads no observations): no confounding elements
      prior.num_confounders = 0;
      prior.confounder_alpha = Eigen::MatrixXd::Zero(0, 4);
      assign_eta(out.observations, 1, EtaKind::kSubject, eta_rng);
      break;
  }
  return out;
}

namespace {

GridworldRun run_method(const GridworldExperimentOptions& o, const Scenario& s, int run, int confounders,
                        GridworldMethod method) {
  const auto start = std::chrono::steady_clock::now();
  GridworldRun result;
  result.run = run;
  result.confounders = confounders;
  result.method = method;
  result.goal = s.task.goal;
  const Mdp& mdp = s.task.mdp;
  LearnOptions learn = learning_run_options(o, run, confounders);
  learn.accelerate = o.accelerate;
  LearnResult learned;
  if (method == GridworldMethod::kTrueTrajectories) {
    learned = learn_reward(mdp, TruthEStep(mdp, s.task.trajectories), learn);
  } else {
    auto [observations, prior] = gridworld_method_data(s, method, o.seed, run, confounders);
    use_alpha_update(prior, o.update);
    prior.c = o.c;
    prior.tie_actions = o.tie_actions;
    ObservationEStepOptions estep_options;
    estep_options.max_alpha_iterations = o.max_alpha_iterations;
    estep_options.alpha_tolerance = o.alpha_tolerance;
    const ObservationEStep estep(mdp, observations.trajectories, prior, estep_options);
    learned = learn_reward(mdp, estep, learn);
    const RestartResult& best = learned.restarts[static_cast<size_t>(learned.selected_restart)];
    if (best.alpha && best.alpha->learn && best.alpha->update == AlphaUpdate::kPosterior)
      result.strength = best.alpha->strength;
    if (method != GridworldMethod::kIgnoreCE && confounders > 0) {
      const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(learned.theta));
      result.source_accuracy =
          source_accuracy(mdp, policy, dirichlet_mean(best.alpha ? *best.alpha : prior), observations);
    }
  }
  const InverseLearningError ile = inverse_learning_error(mdp, s.task.true_weights, learned.theta);
  result.ile = ile.ile;
  result.ile_relative = ile.relative();
  Eigen::Index best_feature = 0;
  learned.theta.maxCoeff(&best_feature);
  result.goal_recovered = best_feature == s.task.goal;
  result.em_evaluations = learned.restarts[static_cast<size_t>(learned.selected_restart)].em_evaluations;  // the cost
  result.log_likelihood = learned.log_likelihood;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

const std::vector<GridworldMethod>& all_gridworld_methods() {
  static const std::vector<GridworldMethod> methods = {
      GridworldMethod::kTrueTrajectories, GridworldMethod::kTrueObservationFunction, GridworldMethod::kUniformEta,
      GridworldMethod::kPlausibleEta, GridworldMethod::kIgnoreCE};
  return methods;
}

std::string method_label(GridworldMethod method) {
  switch (method) {
    case GridworldMethod::kTrueTrajectories:
      return "True Trajectories";
    case GridworldMethod::kTrueObservationFunction:
      return "True Observation Function";
    case GridworldMethod::kUniformEta:
      return "Uniform eta";
    case GridworldMethod::kPlausibleEta:
      return "Plausible eta";
    case GridworldMethod::kIgnoreCE:
      return "Ignore CE";
  }
  return "?";
}

std::string method_key(GridworldMethod method) {
  switch (method) {
    case GridworldMethod::kTrueTrajectories:
      return "true_trajectories";
    case GridworldMethod::kTrueObservationFunction:
      return "true_observation_function";
    case GridworldMethod::kUniformEta:
      return "uniform_eta";
    case GridworldMethod::kPlausibleEta:
      return "plausible_eta";
    case GridworldMethod::kIgnoreCE:
      return "ignore_ce";
  }
  return "?";
}

bool parse_method(const std::string& key, GridworldMethod& method) {
  for (GridworldMethod m : all_gridworld_methods()) {
    if (method_key(m) == key) {
      method = m;
      return true;
    }
  }
  return false;
}

std::vector<GridworldRun> run_gridworld_experiment(const GridworldExperimentOptions& o) {
  struct Item {
    int run;
    int confounders;
  };
  std::vector<Item> items;
  for (int run = 0; run < o.runs; ++run) {
    for (int e : o.confounders) items.push_back({run, e});
  }
  const size_t per_item = o.methods.size();
  std::vector<GridworldRun> results(items.size() * per_item);
  std::atomic<int> done{0};
  const int total = static_cast<int>(results.size());
  parallel_for(static_cast<int>(items.size()), o.threads, [&](int i) {
    const Item& item = items[static_cast<size_t>(i)];
    const Scenario scenario = make_scenario(o, item.run, item.confounders);
    for (size_t m = 0; m < per_item; ++m) {
      GridworldRun& slot = results[static_cast<size_t>(i) * per_item + m];
      try {
        slot = run_method(o, scenario, item.run, item.confounders, o.methods[m]);
      } catch (const std::exception& e) {
        // One failed run must not lose the others: record it and go on.
        slot.run = item.run;
        slot.confounders = item.confounders;
        slot.method = o.methods[m];
        slot.error = e.what();
      }
      const int finished = ++done;
      if (o.progress) o.progress(finished, total);
    }
  });
  return results;
}

std::string gridworld_runs_csv(const std::vector<GridworldRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "run,method,confounders,goal,ile,ile_relative,goal_recovered,em_evaluations,log_likelihood,source_accuracy,"
         "strength,seconds,error\n";
  for (const auto& r : runs) {
    out << r.run << "," << method_key(r.method) << "," << r.confounders << "," << r.goal << "," << r.ile << ","
        << r.ile_relative << "," << (r.goal_recovered ? 1 : 0) << "," << r.em_evaluations << "," << r.log_likelihood
        << ",";
    if (r.source_accuracy >= 0.0) out << r.source_accuracy;
    out << ",";
    if (r.strength >= 0.0) out << r.strength;
    const std::string error = csv_text(r.error);
    out << "," << r.seconds << "," << error << "\n";
  }
  return out.str();
}

}  // namespace hbirl
