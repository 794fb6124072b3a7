// hbirl learn: HiddenDataEM / MaxCausalEnt IRL on a problem file.
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "app/learn.hpp"
#include "commands.hpp"
#include "learner/controlled_prior.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/observation_support.hpp"
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

// app::learn on the problem: from its observations, or (--from truth) its true trajectories.
app::Learned learn_problem(const Problem& problem, const LearnArgs& args) {
  app::LearnHooks hooks;
  if (args.verbose) hooks.on_iteration = report_iterate;
  if (args.from == "truth") {
    try {
      return app::learn_from_truth(problem.mdp, problem.truth_trajectories(), args.settings, hooks);
    } catch (const InputError& e) {
      throw in_file(args.problem, e);
    }
  }
  ProblemObservations in = observations_of(problem, args);
  hooks.trajectory_name = [&in](int i) {
    return "demonstration[" + std::to_string(in.demonstration_index[static_cast<size_t>(i)]) + "]";
  };
  try {
    return app::learn(problem.mdp, in.trajectories, std::move(in.prior), args.settings, hooks);
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
  return {{"subject", subject}, {"confounders", confounders}};
}

// With true weights in the file: the ILE, its relative size and the policy agreement of theta.
void add_true_weight_metrics(nlohmann::ordered_json& out, const Problem& problem, const Eigen::VectorXd& theta,
                             const LearnArgs& args) {
  const Mdp& mdp = problem.mdp;
  const PolicyMetrics metrics = policy_metrics(mdp, *problem.true_weights, theta);
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
nlohmann::ordered_json learned_observation_model_json(const Mdp& mdp, const app::Learned& learned_all,
                                                      const RestartResult& best) {
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
  if (learned_all.learned_eta) om["learned_eta"] = learned_eta_json(*learned_all.learned_eta);
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

int run_learn(const LearnArgs& args) {
  if (!args.log.empty()) return run_learn_from_log(args);
  if (args.problem.empty()) throw InputError("--problem", "give a problem file (or --log with a recorded run)");
  const Problem problem = load_problem(args.problem);
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
  if (problem.true_weights) add_true_weight_metrics(out, problem, learned.theta, args);
  if (observed != nullptr) out["observation_model"] = learned_observation_model_json(mdp, learned_all, best);
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
  CLI::Option* problem = cmd->add_option("--problem,-p", args->problem, "Problem file (JSON, see README.md)");
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
  cmd->add_flag("--verbose,-v", args->verbose, "Report every EM iteration on stderr");
  cmd->add_option("--out,-o", args->out, "Write the JSON result to this file instead of stdout");
  return [args] { return run_learn(*args); };
}

}  // namespace hbirl::cli
