// hbirl posterior: the exact (or MCMC) posterior of each trajectory under given weights.
#include <sstream>

#include "app/command_line.hpp"
#include "app/learn.hpp"
#include "commands.hpp"
#include "learner/estep_observations.hpp"
#include "learner/input_error.hpp"
#include "problem/json_format.hpp"

namespace hbirl::cli {

namespace {

struct PosteriorArgs {
  std::string problem;
  app::LearnSettings engine;  // the posterior engine's settings (app::Front::kEngine)
  std::string weights;
  std::uint64_t seed = 1;
  std::string out;
};

Eigen::VectorXd parse_weights(const std::string& text, int k) {
  Eigen::VectorXd w = Eigen::VectorXd::Zero(k);
  if (text.empty()) return w;
  std::stringstream in(text);
  std::string item;
  int i = 0;
  while (std::getline(in, item, ',')) {
    if (i >= k) throw InputError("--weights", "has more than " + std::to_string(k) + " entries (mdp.num_features)");
    try {
      size_t used = 0;
      w[i] = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(w[i])) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError("--weights", "entry " + std::to_string(i) + " (\"" + item + "\") is not a finite number");
    }
    ++i;
  }
  if (i != k) throw InputError("--weights", "has " + std::to_string(i) + " entries, expected " + std::to_string(k));
  return w;
}

// Every trajectory's observations (the posterior needs them all); path names the file in errors.
std::vector<ObservedTrajectory> demonstrated_observations(const Problem& problem, const std::string& path) {
  std::vector<ObservedTrajectory> observed;
  for (size_t i = 0; i < problem.demonstration.size(); ++i) {
    if (!problem.demonstration[i].steps) {
      throw in_file(path, InputError("demonstration[" + std::to_string(i) + "].steps",
                                     "missing; the posterior needs observations"));
    }
    observed.push_back(*problem.demonstration[i].steps);
  }
  return observed;
}

// Steps whose most probable (s, a) is the true one, of the steps with a truth.
struct MapAccuracy {
  long long correct = 0;
  long long steps = 0;
};

// Step t of a trajectory: its marginals [s, a, p] with p > 0, each observation's posterior
// over its source and, with the truth, the true pair's probability.
nlohmann::ordered_json posterior_step_json(const Mdp& mdp, const DemonstratedTrajectory& item,
                                           const TrajectoryPosterior& post, int t, MapAccuracy& map) {
  nlohmann::ordered_json marginals = nlohmann::ordered_json::array();
  Eigen::Index best = 0;
  post.marginals.row(t).maxCoeff(&best);
  for (int r = 0; r < mdp.num_pairs(); ++r) {
    if (post.marginals(t, r) > 0.0)
      marginals.push_back({r / mdp.num_actions, r % mdp.num_actions, post.marginals(t, r)});
  }
  nlohmann::ordered_json sources = nlohmann::ordered_json::array();
  for (int n = item.steps->step_begin[static_cast<size_t>(t)]; n < item.steps->step_begin[static_cast<size_t>(t) + 1];
       ++n) {
    sources.push_back(
        std::vector<double>(post.sources.row(n).data(), post.sources.row(n).data() + post.sources.cols()));
  }
  nlohmann::ordered_json step;
  step["marginals"] = marginals;
  step["sources"] = sources;
  if (item.truth) {
    const StateAction truth = (*item.truth)[static_cast<size_t>(t)];
    step["truth_probability"] = post.marginals(t, mdp.pair(truth.state, truth.action));
    map.correct += best == mdp.pair(truth.state, truth.action);
    ++map.steps;
  }
  return step;
}

// A trajectory's posterior: its log-likelihood (null, and "impossible", when its
// observations cannot happen; `total` then becomes -infinity) and its steps.
nlohmann::ordered_json posterior_trajectory_json(const Mdp& mdp, const DemonstratedTrajectory& item,
                                                 const TrajectoryPosterior& post, double& total, MapAccuracy& map) {
  nlohmann::ordered_json traj;
  if (std::isfinite(post.log_likelihood)) {
    traj["log_likelihood"] = post.log_likelihood;
    total += post.log_likelihood;
  } else {
    traj["log_likelihood"] = nullptr;
    traj["impossible"] = true;
    total = -std::numeric_limits<double>::infinity();
  }
  nlohmann::ordered_json steps = nlohmann::ordered_json::array();
  for (int t = 0; t < item.steps->length(); ++t) steps.push_back(posterior_step_json(mdp, item, post, t, map));
  traj["steps"] = steps;
  return traj;
}

int run_posterior(const PosteriorArgs& args) {
  const Problem problem = load_problem(args.problem);
  const Mdp& mdp = problem.mdp;
  if (!problem.observation_model) {
    throw in_file(args.problem, InputError("observation_model", "missing; the posterior needs it"));
  }
  const Eigen::VectorXd theta = parse_weights(args.weights, mdp.num_features());
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(theta));
  // Every trajectory's observations, with the unlisted catch-all added when the file asks
  // for one (the same sources `hbirl learn` uses).
  std::vector<ObservedTrajectory> observed = demonstrated_observations(problem, args.problem);
  ObservationPrior prior = *problem.observation_model;
  add_unlisted_source(prior, observed);
  const ObservationModel model = dirichlet_mean(prior);
  std::unique_ptr<PosteriorEngine> engine = app::engine_factory(args.engine)(mdp);
  const Rng root(args.seed);
  nlohmann::ordered_json trajectories = nlohmann::ordered_json::array();
  double total = 0.0;
  MapAccuracy map;
  McmcDiagnostics mcmc;  // worst over the trajectories (neutral for the exact engine)
  for (size_t i = 0; i < problem.demonstration.size(); ++i) {
    const DemonstratedTrajectory& item = problem.demonstration[i];
    Rng rng = root.split(i);
    const TrajectoryPosterior post = engine->posterior(policy, model, observed[i], rng);
    mcmc += post.mcmc;
    trajectories.push_back(posterior_trajectory_json(mdp, item, post, total, map));
  }
  nlohmann::ordered_json out;
  out["engine"] = args.engine.engine;
  out["weights"] = std::vector<double>(theta.data(), theta.data() + theta.size());
  if (std::isfinite(total)) {
    out["log_likelihood"] = total;
  } else {
    out["log_likelihood"] = nullptr;
  }
  if (map.steps > 0) out["map_accuracy"] = static_cast<double>(map.correct) / static_cast<double>(map.steps);
  const bool sampled = args.engine.engine == "mcmc";
  if (sampled) out["mcmc_diagnostics"] = mcmc_diagnostics_json(mcmc);
  out["trajectories"] = trajectories;
  if (sampled) warn_if_not_converged(mcmc);
  emit(format_json(out), args.out);
  return 0;
}

}  // namespace

Command add_posterior(CLI::App& app) {
  auto args = std::make_shared<PosteriorArgs>();
  CLI::App* cmd =
      app.add_subcommand("posterior",
                         "Print the posterior of every trajectory given its observations: the log-likelihood,\n"
                         "per step the (s, a) marginals [s, a, p] with p > 0, and per observation the posterior\n"
                         "over its source [p_subject, p_e0, ...]. The policy is the soft policy of --weights\n"
                         "(default all zero); O is the Dirichlet mean of the file's alpha (not refined). With\n"
                         "truth in the file, each step also gets truth_probability and the output map_accuracy\n"
                         "(share of steps whose most probable pair is the true one).");
  cmd->add_option("--problem,-p", args->problem, "Problem file (JSON, see docs/files.md)")->required();
  app::add_learn_settings(cmd, args->engine, app::Front::kEngine);
  cmd->add_option("--weights,-w", args->weights, "Reward weights theta as w1,w2,... (default: all zero)");
  cmd->add_option("--seed", args->seed, "Seed of the MCMC engine")->capture_default_str();
  cmd->add_option("--out,-o", args->out, "Write the JSON result to this file instead of stdout");
  return [args] { return run_posterior(*args); };
}

}  // namespace hbirl::cli
