// hbirl learn: HiddenDataEM / MaxCausalEnt IRL on a problem file.
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

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

// The observation-based E-step for the problem (every trajectory needs steps).
std::unique_ptr<ObservationEStep> observation_estep(const Problem& problem, const LearnArgs& args) {
  if (!problem.observation_model) {
    throw in_file(args.problem, InputError("observation_model", "missing; learning from observations needs it (or use --from truth)"));
  }
  ProblemObservations in;
  try {
    in = problem_observations(problem);
  } catch (const InputError& e) {
    throw in_file(args.problem, e);
  }
  std::vector<ObservedTrajectory>& trajectories = in.trajectories;
  const std::vector<size_t>& demonstration_index = in.demonstration_index;  // of each trajectory learned from, for messages
  ObservationPrior& prior = in.prior;
  try {
    add_unlisted_source(prior, trajectories);  // before the check: the catch-all can produce anything
  } catch (const InputError& e) {
    throw in_file(args.problem, e);
  }
  if (const auto impossible = first_impossible_observation(problem.mdp, trajectories, prior)) {
    std::string where = "demonstration[" + std::to_string(demonstration_index[static_cast<size_t>(impossible->trajectory)]) +
                        "].steps[" + std::to_string(impossible->step) + "]";
    if (impossible->observation >= 0) where += ".observations[" + std::to_string(impossible->observation) + "]";
    throw in_file(args.problem, InputError(where, "impossible under the observation model: " + impossible->why));
  }
  if (args.update_given) use_alpha_update(prior, args.update);
  if (args.eta == "stated") prior.learn_eta = false;
  if (args.eta == "learned") prior.learn_eta = true;
  ObservationEStepOptions options;
  options.engine = engine_factory(args.engine);
  options.alpha_tolerance = args.alpha_tolerance;
  options.max_alpha_iterations = args.max_alpha_iterations;
  // Restarts run in parallel; a single restart spreads its E-step over the threads instead.
  options.threads = args.restarts == 1 ? args.threads : 1;
  return std::make_unique<ObservationEStep>(problem.mdp, std::move(trajectories), prior, options);
}

nlohmann::ordered_json model_json(const Mdp& mdp, const ObservationModel& model) {
  nlohmann::ordered_json subject = nlohmann::ordered_json::array();
  for (int r = 0; r < mdp.num_pairs(); ++r) {
    const Eigen::VectorXd row = model.subject.row(r).transpose();
    subject.push_back({r / mdp.num_actions, r % mdp.num_actions, to_vector(row)});
  }
  nlohmann::ordered_json confounders = nlohmann::ordered_json::array();
  for (int e = 0; e < model.num_confounders(); ++e) confounders.push_back(to_vector(model.confounders.row(e).transpose()));
  return {{"subject", subject}, {"confounders", confounders}};
}

int run_learn(const LearnArgs& args) {
  if (!args.log.empty()) return run_learn_from_log(args);
  if (args.problem.empty()) throw InputError("--problem", "give a problem file (or --log with a recorded run)");
  const Problem problem = load_problem(args.problem);
  const Mdp& mdp = problem.mdp;
  const bool from_truth = args.from == "truth";
  std::unique_ptr<EStep> estep;
  const ObservationEStep* observed = nullptr;
  if (from_truth) {
    std::vector<Trajectory> truth;
    try {
      truth = problem.truth_trajectories();
    } catch (const InputError& e) {
      throw in_file(args.problem, e);
    }
    estep = std::make_unique<TruthEStep>(mdp, std::move(truth));
  } else {
    auto e = observation_estep(problem, args);
    observed = e.get();
    estep = std::move(e);
  }

  LearnOptions options;
  options.optimizer.kind = args.optimizer == "eg" ? OptimizerKind::kExponentiatedGradient : OptimizerKind::kLbfgs;
  options.optimizer.max_iterations = args.max_iterations;
  options.optimizer.gradient_tolerance = args.tolerance;
  options.optimizer.eg_radius = args.eg_radius;
  options.optimizer.eg_learning_rate = args.eg_rate;
  options.l2 = args.l2;
  options.restarts = args.restarts;
  options.seed = args.seed;
  options.threads = args.threads;
  options.max_em_iterations = args.max_em_iterations;
  options.accelerate = args.engine.name != "mcmc";  // SQUAREM needs a deterministic E-step
  if (args.verbose) {
    options.on_iteration = [](int restart, int iteration, double objective, const Eigen::VectorXd& theta,
                              const EStepResult& e, const ObservationPrior* alpha) {
      std::ostringstream line;
      line << "hbirl: restart " << restart << " EM iteration " << iteration << ": objective " << objective
           << ", log-likelihood " << e.log_likelihood << ", theta [" << theta.transpose() << "], observation-model updates "
           << e.alpha_iterations << (e.alpha_converged ? " (converged)" : "");
      if (alpha && alpha->learn && alpha->update == AlphaUpdate::kPosterior) line << ", prior strength " << alpha->strength;
      line << "\n";
      std::cerr << line.str();
    };
  }
  const LearnResult learned = learn_reward(mdp, *estep, options);
  const RestartResult& best = learned.restarts[static_cast<size_t>(learned.selected_restart)];

  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(learned.theta));
  Eigen::VectorXd counts;
  std::optional<ObservationModel> model;
  std::optional<McmcDiagnostics> mcmc;  // of this last E-step pass, at the returned point
  if (observed != nullptr) {
    model = dirichlet_mean(best.alpha ? *best.alpha : observed->prior());  // the prior learned from (controlled run, catch-all)
    const ObservationPrior& learned_from = best.alpha ? *best.alpha : observed->prior();
    const std::optional<RowMatrix> eta = observed->learned_eta(learned_from);  // the model's eta, when learned
    const EStepStatistics stats = observed->statistics(policy, *model, args.seed, eta ? &*eta : nullptr);
    counts = stats.counts;
    if (args.engine.name == "mcmc") mcmc = stats.mcmc;
  } else {
    EStepState state = estep->initial_state(0);
    counts = estep->expect(policy, state).counts;
  }
  nlohmann::ordered_json out;
  out["weights"] = to_vector(learned.theta);
  if (!problem.feature_names.empty()) out["feature_names"] = problem.feature_names;
  out["log_likelihood"] = learned.log_likelihood;
  out["from"] = args.from;
  if (!from_truth) out["engine"] = args.engine.name;
  if (mcmc) out["mcmc_diagnostics"] = mcmc_diagnostics_json(*mcmc);
  out["objective"] = "causal_log_likelihood";
  out["optimizer"] = to_string(options.optimizer.kind);
  out["em_iterations"] = best.em_iterations;
  out["em_evaluations"] = best.em_evaluations;
  out["feature_count_error"] = feature_count_error(mdp, counts, estep->trajectory_lengths(), policy.policy);
  if (problem.true_weights) {
    const PolicyMetrics metrics = policy_metrics(mdp, *problem.true_weights, learned.theta);
    const InverseLearningError& ile = metrics.ile;
    if (!std::isfinite(ile.ile) || !std::isfinite(ile.relative())) {
      throw in_file(args.problem, InputError("true_weights", "give an ILE that is not a finite number: the true rewards are too large"));
    }
    out["ile"] = ile.ile;
    out["ile_relative"] = ile.relative();
    out["policy_agreement"] = metrics.agreement;
    out["true_weights"] = to_vector(*problem.true_weights);
  }
  if (model) {
    nlohmann::ordered_json om = model_json(mdp, *model);
    const ObservationPrior& used = best.alpha ? *best.alpha : observed->prior();
    om["update"] = used.learn ? alpha_update_name(used.update) : "fixed";
    // The catch-all for unlisted confounders is the last of "confounders" and of every eta.
    if (used.unlisted_added) om["unlisted_source"] = {{"eta", used.unlisted_eta}, {"index", used.num_confounders - 1}};
    if (used.learn && used.update == AlphaUpdate::kPosterior) {
      om["prior_strength"] = used.strength;
      om["prior_strength_chosen"] = used.automatic_strength;
      if (best.held_out_log_likelihood) om["held_out_log_likelihood"] = *best.held_out_log_likelihood;
    }
    if (const std::optional<LearnedEta> eta = observed->learned_eta_report(used)) om["learned_eta"] = learned_eta_json(*eta);
    out["observation_model"] = om;
  }
  out["selected_restart"] = learned.selected_restart;
  nlohmann::ordered_json restarts = nlohmann::ordered_json::array();
  for (const RestartResult& r : learned.restarts) {
    nlohmann::ordered_json item;
    item["initial_weights"] = to_vector(r.initial_theta);
    item["weights"] = to_vector(r.theta);
    item["log_likelihood"] = r.log_likelihood;
    item["em_objective"] = r.objective;  // log-likelihood plus the prior's terms (docs/MODEL.md)
    if (r.held_out_log_likelihood) item["held_out_log_likelihood"] = *r.held_out_log_likelihood;
    if (r.alpha && r.alpha->learn && r.alpha->update == AlphaUpdate::kPosterior) item["prior_strength"] = r.alpha->strength;
    item["score"] = r.score;
    item["em_iterations"] = r.em_iterations;
    item["em_evaluations"] = r.em_evaluations;
    item["optimizer_iterations"] = r.optimizer_iterations;
    item["converged"] = r.converged;
    item["status"] = r.optimizer_status;
    restarts.push_back(item);
  }
  out["restarts"] = restarts;
  for (const RestartResult& r : learned.restarts) {
    if (!r.converged) {
      std::cerr << "hbirl: warning: a restart stopped before converging ("
                << (r.em_evaluations >= options.max_em_iterations && estep->depends_on_policy()
                        ? "EM iteration limit " + std::to_string(options.max_em_iterations)
                        : "M-step: " + r.optimizer_status)
                << "); see \"restarts\" in the output\n";
      break;
    }
  }
  if (mcmc) warn_if_not_converged(*mcmc);
  emit(format_json(out), args.out);
  return 0;
}

}  // namespace

Command add_learn(CLI::App& app) {
  auto args = std::make_shared<LearnArgs>();
  CLI::App* cmd = app.add_subcommand(
      "learn",
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
  add_domain_options(cmd, args->domain,
                     "With --log: the domain file the run was on (built-in domains, onion and gridworld, are named in the log)");
  add_key_option(cmd, args->key_file);
  cmd->add_flag("--allow-incomplete", args->allow_incomplete,
                "With --log: learn from a recording whose run never reached its end (END_RUN), from the episodes\n"
                "that finished; the output's \"incomplete\" says what is missing (without it such a log is refused)");
  cmd->add_option("--from", args->from,
                  "What to learn from: 'observations' (HiddenDataEM on the observations) or "
                  "'truth' (MaxCausalEnt on the truth trajectories)")
      ->check(CLI::IsMember({"observations", "truth"}))
      ->capture_default_str();
  cmd->add_option("--optimizer", args->optimizer,
                  "M-step optimiser: 'lbfgs' (L-BFGS) or 'eg' (the paper's adaptive exponentiated gradient)")
      ->check(CLI::IsMember({"lbfgs", "eg"}))
      ->capture_default_str();
  cmd->add_option("--l2", args->l2, "L2 penalty weight on theta, per demonstrated step")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--restarts", args->restarts,
                  "Restarts: the first from theta = 0, the others from U[-1,1]^K; the one with the "
                  "highest (penalised) log-likelihood wins (the held-out log-likelihood when the prior "
                  "strength is chosen from the data)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Seed of every random choice")->capture_default_str();
  cmd->add_option("--threads", args->threads,
                  "Threads for the restarts (0 = one per core); the result does not depend on it")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  cmd->add_option("--max-iterations", args->max_iterations, "Optimiser iteration limit per M-step")
      ->check(CLI::Range(1, 100000000))
      ->capture_default_str();
  cmd->add_option("--tolerance", args->tolerance,
                  "Optimiser stops when ||gradient|| <= tolerance * max(1, ||theta||)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--eg-radius", args->eg_radius, "EG only: search the L1 ball ||theta||_1 <= radius")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--eg-rate", args->eg_rate, "EG only: learning rate eta (<= 0.25 for its regret bound)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  add_engine_options(cmd, args->engine);
  cmd->add_option("--max-em-iterations", args->max_em_iterations, "HiddenDataEM's budget of E-step + M-step evaluations (SQUAREM's rejected extrapolations count; \"em_evaluations\" in the output)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--alpha-tolerance", args->alpha_tolerance,
                  "The observation model has converged when O moves less than this (see docs/MODEL.md)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--max-alpha-iterations", args->max_alpha_iterations,
                  "Observation-model refinements per E-step (EM continues until O has converged)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  CLI::Option* update = add_alpha_update_option(cmd, args->update);
  update->default_str("the file's observation_model.update");
  cmd->add_option("--eta", args->eta,
                  "'stated': take every observation's eta as given; 'learned': learn it per context (docs/MODEL.md); "
                  "'file': as the file's (or with --log, the domain's) observation_model.learn_eta says (default: learned "
                  "with the posterior update). hbirl-optimiser learns it the same way (its --eta)")
      ->check(CLI::IsMember({"file", "stated", "learned"}))
      ->capture_default_str();
  cmd->add_flag("--verbose,-v", args->verbose, "Report every EM iteration on stderr");
  cmd->add_option("--out,-o", args->out, "Write the JSON result to this file instead of stdout");
  return [args, update] {
    args->update_given = update->count() > 0;
    return run_learn(*args);
  };
}

}  // namespace hbirl::cli
