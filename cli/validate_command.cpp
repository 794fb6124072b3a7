// hbirl validate: check a problem file and summarise it.
#include "commands.hpp"
#include "problem/json_format.hpp"

namespace hbirl::cli {

namespace {

int run_validate(const std::string& path) {
  const Problem problem = load_problem(path);
  const Mdp& mdp = problem.mdp;
  long long steps = 0;
  long long observations = 0;
  long long occluded = 0;
  int with_truth = 0;
  int with_steps = 0;
  for (const auto& t : problem.demonstration) {
    if (t.truth) ++with_truth;
    if (t.steps) {
      ++with_steps;
      steps += t.steps->length();
      observations += t.steps->num_observations();
      for (int i = 0; i < t.steps->length(); ++i) occluded += t.steps->observations_at(i) == 0;
    } else if (t.truth) {
      steps += static_cast<long long>(t.truth->size());
    }
  }
  int terminal = 0;
  for (int s = 0; s < mdp.num_states; ++s) terminal += mdp.is_terminal(s);
  nlohmann::ordered_json out;
  out["valid"] = true;
  out["num_states"] = mdp.num_states;
  out["num_actions"] = mdp.num_actions;
  out["num_features"] = mdp.num_features();
  out["num_transitions"] = mdp.transitions.nonZeros();
  out["terminal_states"] = terminal;
  out["discount"] = mdp.discount;
  out["trajectories"] = problem.demonstration.size();
  out["trajectories_with_truth"] = with_truth;
  out["trajectories_with_observations"] = with_steps;
  out["steps"] = steps;
  out["observations"] = observations;
  out["occluded_steps"] = occluded;
  if (problem.observation_model) {
    out["num_symbols"] = problem.observation_model->num_symbols;
    out["num_confounders"] = problem.observation_model->num_confounders;
  }
  out["has_true_weights"] = problem.true_weights.has_value();
  emit(format_json(out), "");
  return 0;
}

}  // namespace

Command add_validate(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "validate",
      "Check a problem file and print a JSON summary (sizes, trajectories, steps,\n"
      "observations, occluded steps). Problems are reported as one line on stderr naming\n"
      "the field and position, with exit status 2; unknown keys only warn.");
  cmd->add_option("--problem,-p", *path, "Problem file (JSON, see README.md)")->required();
  return [path] { return run_validate(*path); };
}

}  // namespace hbirl::cli
