// hbirl validate: check a problem file or a domain file and summarise it.
#include <cstdio>
#include <iostream>

#include "commands.hpp"
#include "full_commands.hpp"
#include "sim_driver/registry/domain.hpp"
#include "problem/domain_file.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/trajectory.hpp"
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

// How often the simulated expert (the soft policy of true_weights, as the domain's simulator
// draws it) enters a terminal state within the sensor's `length` steps; a warning when it
// is less than half of its trajectories: the demonstrations then rarely show where it was
// going, and the run learns a reward of about 0 (a larger length, or a start nearer).
void warn_if_the_expert_rarely_ends(const std::string& path, const DomainSpec& d, nlohmann::ordered_json& sensor) {
  // length x transitions work: a bound keeps validate quick on the largest domain files.
  if (static_cast<double>(d.sensor->length) * static_cast<double>(d.mdp.transitions.nonZeros()) > 5e8) return;
  const SoftSolution expert = soft_value_iteration(d.mdp, d.mdp.reward(*d.true_weights));
  if (!expert.converged) return;  // the services refuse it, saying so
  const double p = probability_of_ending_within(d.mdp, expert.policy, d.sensor->length);
  sensor["expert_ends_within_length"] = p;
  if (p >= 0.5) return;
  char share[32];
  std::snprintf(share, sizeof share, "%.1f%%", 100.0 * p);
  std::cerr << "hbirl: warning: " << path << ": sensor.length: the expert (true_weights' soft policy) enters a "
            << "terminal state within " << d.sensor->length << " steps in only " << share
            << " of its trajectories: the demonstrations will rarely show where it is going (a larger length, or "
               "a start nearer the goal)\n";
}

// A domain file (docs/your-task.md "Your own task"): its sizes, names and sensor.
int run_validate_domain(const std::string& path) {
  std::vector<std::string> warnings;
  DomainSpec d;
  try {
    d = read_domain_file(path, &warnings);
  } catch (const FileError& e) {
    throw InputError("--domain " + path, e.message());
  } catch (const InputError& e) {
    throw in_file(path, e);
  }
  warn_all(path, warnings);
  open_domain(path);  // what the services would open (e.g. a built-in domain's name is refused)
  int terminal = 0;
  for (int s = 0; s < d.mdp.num_states; ++s) terminal += d.mdp.is_terminal(s);
  nlohmann::ordered_json out;
  out["valid"] = true;
  out["name"] = d.name;
  out["num_states"] = d.mdp.num_states;
  out["num_actions"] = d.mdp.num_actions;
  out["num_features"] = d.mdp.num_features();
  out["num_transitions"] = d.mdp.transitions.nonZeros();
  out["terminal_states"] = terminal;
  out["discount"] = d.mdp.discount;
  out["num_symbols"] = d.num_symbols();
  out["num_sources"] = d.num_sources();
  out["has_true_weights"] = d.true_weights.has_value();
  out["has_observation_model"] = d.observation_model.has_value();
  if (d.sensor) {
    const SensorSpec& s = *d.sensor;
    out["sensor"] = {{"observations_per_step", s.observations_per_step},
                     {"eta", s.eta},
                     {"occlusion", s.occlusion},
                     {"trajectories", s.trajectories},
                     {"length", s.length},
                     {"controlled_trajectories", s.controlled_trajectories}};
    if (d.true_weights && terminal > 0) warn_if_the_expert_rarely_ends(path, d, out["sensor"]);
  } else {
    out["sensor"] = nullptr;
  }
  emit(format_json(out), "");
  return 0;
}

}  // namespace

Command add_validate(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  auto domain = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(kValidate.name, kValidate.description);
  CLI::Option* problem = cmd->add_option("--problem,-p", *path, "Problem file (JSON, see docs/files.md)");
  CLI::Option* domain_file = cmd->add_option("--domain", *domain, "Domain file (JSON, docs/your-task.md)");
  problem->excludes(domain_file);
  cmd->require_option(1);
  return [path, domain] { return domain->empty() ? run_validate(*path) : run_validate_domain(*domain); };
}

}  // namespace hbirl::cli
