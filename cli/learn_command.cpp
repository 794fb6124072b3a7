// hbirl learn: HiddenDataEM / MaxCausalEnt IRL on a problem file.
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "app/learn.hpp"
#include "app/output.hpp"
#include "commands.hpp"
#include "learner/controlled_prior.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/observation_model.hpp"
#include "learner/observation_support.hpp"
#include "learner/value_iteration.hpp"
#include "problem/json_format.hpp"
#include "problem/problem_observations.hpp"
#include "learn_args.hpp"

namespace hbirl::cli {

namespace {

std::vector<double> to_vector(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

// What a problem file gives to learn from observations: the demonstrations' observations,
// the observation prior and, for messages, each trajectory's demonstration index.
ProblemObservations observations_of(const Problem& problem, const LearnArgs& args) {
  if (!problem.observation_model) {
    throw in_file(args.problem, InputError("observation_model",
                                           "missing; learning from observations needs it (or use --from truth)"));
  }
  try {
    return problem_observations(problem);
  } catch (const InputError& e) {
    throw in_file(args.problem, e);
  }
}

// One line per EM iterate on stderr (--verbose).
void report_iterate(const app::Iterate& i) {
  std::ostringstream line;
  line << "hbirl: restart " << i.restart << " EM iteration " << i.iteration << ": objective " << i.objective
       << ", log-likelihood " << i.estep.log_likelihood << ", theta [" << i.theta.transpose()
       << "], observation-model updates " << i.estep.alpha_iterations
       << (i.estep.alpha_converged ? " (converged)" : "");
  const ObservationPrior* alpha = i.refined;
  if (alpha && alpha->learn && alpha->update == AlphaUpdate::kPosterior) line << ", prior strength " << alpha->strength;
  line << "\n";
  std::cerr << line.str();
}

// The first `n` of a problem's demonstrations (0: all), as --demonstrations asks.
template <typename T>
void keep_first(std::vector<T>& items, int n) {
  if (n == 0) return;
  if (static_cast<size_t>(n) > items.size()) {
    throw InputError("--demonstrations", "is " + std::to_string(n) + " but the file has " +
                                             std::to_string(items.size()) + " to learn from");
  }
  items.resize(static_cast<size_t>(n));
}

// What a problem file gives app::learn: its true trajectories (--from truth) or its
// observations, the first --demonstrations of them, and how to name one in an error.
struct ProblemData {
  std::vector<Trajectory> truth;
  ProblemObservations observed;
  app::LearnHooks hooks;
};

ProblemData problem_data(const Problem& problem, const LearnArgs& args) {
  ProblemData data;
  if (args.verbose) data.hooks.on_iteration = report_iterate;
  try {
    if (args.from == "truth") {
      data.truth = problem.truth_trajectories();
      keep_first(data.truth, args.demonstrations);
      return data;
    }
    data.observed = observations_of(problem, args);
  } catch (const InputError& e) {
    throw in_file(args.problem, e);
  }
  keep_first(data.observed.trajectories, args.demonstrations);
  data.hooks.trajectory_name = [index = data.observed.demonstration_index](int i) {
    return "demonstration[" + std::to_string(index[static_cast<size_t>(i)]) + "]";
  };
  return data;
}

// app::learn on the problem: from its observations, or (--from truth) its true trajectories.
app::Learned learn_problem(const Problem& problem, const LearnArgs& args) {
  ProblemData data = problem_data(problem, args);
  try {
    if (args.from == "truth")
      return app::learn_from_truth(problem.mdp, std::move(data.truth), args.settings, data.hooks);
    return app::learn(problem.mdp, data.observed.trajectories, std::move(data.observed.prior), args.settings,
                      data.hooks);
  } catch (const InputError& e) {
    throw in_file(args.problem, e);
  }
}

nlohmann::ordered_json model_json(const Mdp& mdp, const ObservationModel& model) {
  nlohmann::ordered_json subject = nlohmann::ordered_json::array();
  for (int r = 0; r < mdp.num_pairs(); ++r) {
    const Eigen::VectorXd row = model.subject.row(r).transpose();
    subject.push_back({r / mdp.num_actions, r % mdp.num_actions, to_vector(row)});
  }
  nlohmann::ordered_json confounders = nlohmann::ordered_json::array();
  for (int e = 0; e < model.num_confounders(); ++e)
    confounders.push_back(to_vector(model.confounders.row(e).transpose()));
  nlohmann::ordered_json out = {{"subject", subject}, {"confounders", confounders}};
  if (model.end.size() > 0) {  // the end sensor's O_end, per terminal state: [state, probabilities]
    nlohmann::ordered_json end = nlohmann::ordered_json::array();
    for (int s = 0; s < mdp.num_states; ++s) {
      if (mdp.is_terminal(s)) end.push_back({s, to_vector(model.end.row(s).transpose())});
    }
    out["end_sensor"] = end;
  }
  return out;
}

// With true weights in the file: the ILE, its relative size and the policy agreement of theta.
void add_true_weight_metrics(nlohmann::ordered_json& out, const Problem& problem, const OptimalPolicy& learned,
                             const LearnArgs& args) {
  const Mdp& mdp = problem.mdp;
  const PolicyMetrics metrics = policy_metrics(mdp, *problem.true_weights, learned);
  const InverseLearningError& ile = metrics.ile;
  if (!std::isfinite(ile.ile) || !std::isfinite(ile.relative())) {
    throw in_file(args.problem, InputError("true_weights",
                                           "give an ILE that is not a finite number: the true rewards are too large"));
  }
  out["ile"] = ile.ile;
  out["ile_relative"] = ile.relative();
  out["policy_agreement"] = metrics.agreement;
  out["true_weights"] = to_vector(*problem.true_weights);
}

// "observation_model": the learned model, how it was learned and, when learned, eta.
// `context_names`: learned eta's rows by name (the problem file's, when its observations
// all came with contexts).
nlohmann::ordered_json learned_observation_model_json(const Mdp& mdp, const app::Learned& learned_all,
                                                      const RestartResult& best,
                                                      const std::vector<std::string>& context_names) {
  nlohmann::ordered_json om = model_json(mdp, learned_all.model);
  const ObservationPrior& used = learned_all.refined;
  om["update"] = used.learn ? alpha_update_name(used.update) : "fixed";
  // The catch-all for unlisted confounders is the last of "confounders" and of every eta.
  if (used.unlisted_added) om["unlisted_source"] = {{"eta", used.unlisted_eta}, {"index", used.num_confounders - 1}};
  if (used.learn && used.update == AlphaUpdate::kPosterior) {
    om["prior_strength"] = used.strength;
    om["prior_strength_chosen"] = used.automatic_strength;
    if (best.held_out_log_likelihood) om["held_out_log_likelihood"] = *best.held_out_log_likelihood;
  }
  // The share of each row's base given to its state's other actions (docs/MODEL.md "A
  // state's actions share their view"), when the file asked for the tie: a learned O starts
  // from it, a held O is held at it.
  if (ties_subject_prior(used)) om["tie_share"] = used.subject_tie;
  if (learned_all.learned_eta) om["learned_eta"] = learned_eta_json(*learned_all.learned_eta, context_names);
  return om;
}

// Importance weights that few draws carry: the posterior's numbers are rough.
void warn_if_rough(const RewardPosterior& p) {
  if (p.effective_samples >= 0.1 * static_cast<double>(p.samples.rows())) return;
  std::cerr << "hbirl learn: warning: the posterior's draws are worth " << p.effective_samples << " of "
            << p.samples.rows() << " (the Laplace proposal fits it poorly): its numbers are rough\n";
}

// "restarts": each restart's start, result and how its EM and M-step ended.
nlohmann::ordered_json restarts_json(const LearnResult& learned) {
  nlohmann::ordered_json restarts = nlohmann::ordered_json::array();
  for (const RestartResult& r : learned.restarts) {
    nlohmann::ordered_json item;
    item["initial_weights"] = to_vector(r.initial_theta);
    item["weights"] = to_vector(r.theta);
    item["log_likelihood"] = r.log_likelihood;
    item["em_objective"] = r.objective;  // log-likelihood plus the prior's terms (docs/MODEL.md)
    if (r.held_out_log_likelihood) item["held_out_log_likelihood"] = *r.held_out_log_likelihood;
    if (r.alpha && r.alpha->learn && r.alpha->update == AlphaUpdate::kPosterior)
      item["prior_strength"] = r.alpha->strength;
    item["score"] = r.score;
    item["em_iterations"] = r.em_iterations;
    item["em_evaluations"] = r.em_evaluations;
    item["optimizer_iterations"] = r.optimizer_iterations;
    item["converged"] = r.converged;
    item["status"] = r.optimizer_status;
    restarts.push_back(item);
  }
  return restarts;
}

// One line on stderr when a restart stopped before converging: the first such, and why.
void warn_unconverged_restart(const LearnResult& learned, const LearnArgs& args, const EStep& estep) {
  for (const RestartResult& r : learned.restarts) {
    if (!r.converged) {
      std::cerr << "hbirl: warning: a restart stopped before converging ("
                << (r.em_evaluations >= args.settings.em.max_em_iterations && estep.depends_on_policy()
                        ? "EM iteration limit " + std::to_string(args.settings.em.max_em_iterations)
                        : "M-step: " + r.optimizer_status)
                << "); see \"restarts\" in the output\n";
      break;
    }
  }
}

// One estimate of --anytime, a line of JSON: after how many demonstrations, the weights,
// whether EM's selected start was the previous estimate, the greedy policy, the
// log-likelihood, with true weights the ILE, and the posterior's summary when drawn.
nlohmann::ordered_json estimate_json(const Problem& problem, int demonstrations, const app::Learned& learned,
                                     const LearnArgs& args) {
  const Mdp& mdp = problem.mdp;
  nlohmann::ordered_json out;
  out["demonstrations"] = demonstrations;
  out["weights"] = to_vector(learned.em.theta);
  out["log_likelihood"] = learned.em.log_likelihood;
  out["score"] = learned.best().score;
  out["from_previous"] = learned.em.selected_restart == static_cast<int>(learned.em.restarts.size()) - 1 &&
                         learned.em.restarts.size() > static_cast<size_t>(args.settings.em.restarts);
  out["policy"] = value_iteration(mdp, mdp.reward(learned.em.theta)).actions;
  if (problem.true_weights) {
    const InverseLearningError ile = inverse_learning_error(mdp, *problem.true_weights, learned.em.theta);
    out["ile_relative"] = ile.relative();
  }
  if (learned.posterior) out["posterior"] = app::posterior_summary(learned);
  return out;
}

// --anytime: the estimate after each demonstration, one JSON line each, as it is learned.
int run_learn_anytime(const Problem& problem, const LearnArgs& args) {
  ProblemData data = problem_data(problem, args);
  std::string lines;
  const app::EstimateReport print = [&](int n, const app::Learned& learned) {
    const std::string line = estimate_json(problem, n, learned, args).dump() + "\n";
    if (args.out.empty()) {
      emit(line, "");
    } else {
      lines += line;
    }
  };
  try {
    if (args.from == "truth") {
      app::learn_from_truth_anytime(problem.mdp, data.truth, args.settings, data.hooks, print);
    } else {
      app::learn_anytime(problem.mdp, data.observed.trajectories, data.observed.prior, args.settings, data.hooks,
                         print);
    }
  } catch (const InputError& e) {
    throw in_file(args.problem, e);
  }
  if (!args.out.empty()) emit(lines, args.out);
  return 0;
}

// The settings with --warm-start's weights (checked against the problem's features).
LearnArgs with_warm_start(const LearnArgs& args, const Mdp& mdp) {
  LearnArgs out = args;
  if (args.warm_start.empty()) return out;
  if (static_cast<int>(args.warm_start.size()) != mdp.num_features()) {
    throw InputError("--warm-start", "has " + std::to_string(args.warm_start.size()) + " weights; the problem has " +
                                         std::to_string(mdp.num_features()) + " features");
  }
  for (double w : args.warm_start) {
    if (!std::isfinite(w)) throw InputError("--warm-start", "has a weight that is not a finite number");
  }
  out.settings.em.warm_start =
      Eigen::Map<const Eigen::VectorXd>(args.warm_start.data(), static_cast<Eigen::Index>(args.warm_start.size()));
  return out;
}

int run_learn(const LearnArgs& given) {
  if (!given.log.empty()) return run_learn_from_log(given);
  if (given.problem.empty()) throw InputError("--problem", "give a problem file (or --log with a recorded run)");
  const Problem problem = load_problem(given.problem);
  const LearnArgs args = with_warm_start(given, problem.mdp);
  if (args.anytime) return run_learn_anytime(problem, args);
  const Mdp& mdp = problem.mdp;
  const bool from_truth = args.from == "truth";
  const app::Learned learned_all = learn_problem(problem, args);
  const LearnResult& learned = learned_all.em;
  const RestartResult& best = learned_all.best();
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(learned.theta));
  const EStepStatistics stats = learned_all.final_statistics(mdp);  // at the returned point
  const Eigen::VectorXd& counts = stats.counts;
  const ObservationEStep* observed = learned_all.observed;
  std::optional<McmcDiagnostics> mcmc;
  if (observed != nullptr && args.settings.engine == "mcmc") mcmc = stats.mcmc;
  const std::unique_ptr<EStep>& estep = learned_all.estep;
  nlohmann::ordered_json out;
  out["weights"] = to_vector(learned.theta);
  if (!problem.feature_names.empty()) out["feature_names"] = problem.feature_names;
  out["log_likelihood"] = learned.log_likelihood;
  out["from"] = args.from;
  if (!from_truth) out["engine"] = args.settings.engine;
  if (mcmc) out["mcmc_diagnostics"] = mcmc_diagnostics_json(*mcmc);
  out["objective"] = "causal_log_likelihood";
  out["optimizer"] = to_string(args.settings.em.optimizer.kind);
  out["em_iterations"] = best.em_iterations;
  out["em_evaluations"] = best.em_evaluations;
  out["feature_count_error"] = feature_count_error(mdp, counts, estep->trajectory_lengths(), policy.policy);
  const OptimalPolicy planned = value_iteration(mdp, mdp.reward(learned.theta));  // for the metrics and "policy"
  if (problem.true_weights) add_true_weight_metrics(out, problem, planned, args);
  out["policy"] = app::policy_json<nlohmann::ordered_json>(app::learned_policy(mdp, planned, policy.policy),
                                                           problem.state_names, problem.action_names);
  if (observed != nullptr) {
    // (the file's contexts: the E-step's trajectories have one for each distinct eta when it gave none)
    std::vector<ObservedTrajectory> as_given;
    for (const auto& d : problem.demonstration) {
      if (d.steps && !d.controlled && !problem.context_names.empty()) as_given.push_back(*d.steps);
    }
    const std::vector<std::string> no_names;
    out["observation_model"] = learned_observation_model_json(
        mdp, learned_all, best, every_observation_has_context(as_given) ? problem.context_names : no_names);
  }
  if (learned_all.posterior) {
    out["posterior"] = app::posterior_summary(learned_all);
    warn_if_rough(*learned_all.posterior);
  }
  out["selected_restart"] = learned.selected_restart;
  out["restarts"] = restarts_json(learned);
  warn_unconverged_restart(learned, args, *estep);
  if (mcmc) warn_if_not_converged(*mcmc);
  emit(format_json(out), args.out);
  return 0;
}

}  // namespace

Command add_learn(CLI::App& app) {
  auto args = std::make_shared<LearnArgs>();
  CLI::App* cmd =
      app.add_subcommand("learn",
                         "Learn the expert's reward weights from a problem file and print them as JSON.\n"
                         "--from truth runs MaxCausalEnt IRL on the true trajectories (the 'True Trajectories'\n"
                         "baseline). The M-step maximises the causal log-likelihood of the demonstrated\n"
                         "state-action visits under the stationary soft policy (see docs/MODEL.md). Output keys:\n"
                         "weights, log_likelihood, feature_count_error, and with true_weights in the file also\n"
                         "ile (||V^piE - V^piL||_1 under the true reward), ile_relative (ile / ||V^piE||_1) and\n"
                         "policy_agreement; then one entry per restart.");
  CLI::Option* problem = cmd->add_option("--problem,-p", args->problem, "Problem file (JSON, see docs/files.md)");
  CLI::Option* log =
      cmd->add_option("--log", args->log,
                      "Learn from a run of the service set recorded with lcm-logger (services/launch.sh --record): "
                      "the same data and learning as hbirl-optimiser, so the same theta")
          ->excludes(problem);
  app::add_domain_options(
      cmd, args->domain,
      "With --log: the domain file the run was on (built-in domains, onion and gridworld, are named in the log)");
  app::add_key_option(cmd, args->key_file, "with --log, " + app::kRecordingKeyHelp);
  cmd->add_flag("--allow-incomplete", args->allow_incomplete,
                "With --log: learn from a recording whose run never reached its end (END_RUN), from the episodes\n"
                "that finished; the output's \"incomplete\" says what is missing (without it such a log is refused)");
  cmd->add_option("--from", args->from,
                  "What to learn from: 'observations' (HiddenDataEM on the observations) or "
                  "'truth' (MaxCausalEnt on the truth trajectories)")
      ->check(CLI::IsMember({"observations", "truth"}))
      ->capture_default_str();
  app::add_learn_settings(cmd, args->settings, app::Front::kCommandLine);
  cmd->add_option("--demonstrations", args->demonstrations,
                  "Learn from the file's first N demonstrations only (the controlled run not counted)")
      ->check(CLI::Range(1, 1 << 30))
      ->excludes(log);
  cmd->add_option("--warm-start", args->warm_start,
                  "EM also starts from these weights (comma-separated, one per feature) and keeps the better "
                  "start by its selection rule: with --demonstrations n and estimate n-1 of --anytime, this "
                  "reproduces estimate n")
      ->delimiter(',')
      ->excludes(log);
  cmd->add_flag("--anytime", args->anytime,
                "Learn while the demonstrations arrive: after each demonstration n, print one line of JSON "
                "(demonstrations, weights, log_likelihood, score, from_previous, policy, with true weights "
                "ile_relative, with --posterior-samples the posterior) -- what --demonstrations n gives with "
                "--warm-start at estimate n-1 (docs/MODEL.md \"Learning while it watches\")")
      ->excludes(log);
  cmd->add_flag("--verbose,-v", args->verbose, "Report every EM iteration on stderr");
  cmd->add_option("--out,-o", args->out, "Write the JSON result to this file instead of stdout");
  return [args] { return run_learn(*args); };
}

}  // namespace hbirl::cli
