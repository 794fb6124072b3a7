// hbirl generate --domain F (generate_args.hpp): the run the domain's "sensor" section
// simulates -- what hbirl-sim-driver publishes for it -- as a problem file.
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "generate_args.hpp"
#include "learner/input_error.hpp"
#include "problem/json_format.hpp"
#include "sim_driver/registry/domain.hpp"
#include "sim_driver/registry/simulation_options.hpp"

namespace hbirl::cli {

int run_generate_from_domain(const GenerateDomainArgs& args) {
  std::vector<std::string> warnings;
  const std::unique_ptr<Domain> domain = file_domain(args.domain, &warnings);
  for (const auto& w : warnings) std::cerr << "hbirl generate: " << args.domain << ": " << w << "\n";
  SimulationOptions options;
  options.seed = args.seed;
  const std::unique_ptr<Simulation> run = domain->simulate(options);
  Problem problem;
  problem.name = domain->name();
  problem.mdp = domain->mdp();
  const DomainNames names = domain->names(run->num_sources);
  problem.state_names = names.states;
  problem.action_names = names.actions;
  problem.feature_names = names.features;
  problem.context_names = names.contexts;
  problem.observation_model = domain->stated_prior();
  if (run->true_weights.size() > 0) problem.true_weights = run->true_weights;
  int controlled = 0;
  for (int id = 0; id < static_cast<int>(run->episodes.size()); ++id) {
    const Simulation::Episode& e = run->episodes[static_cast<size_t>(id)];
    DemonstratedTrajectory d;
    d.steps = run->observed(id);
    d.truth = e.steps;  // simulated: the true steps are known (the metrics; --from truth)
    d.controlled = e.controlled;
    d.ends_in_terminal = e.ends_in_terminal;
    d.steps->ends_in_terminal = e.ends_in_terminal;
    controlled += e.controlled;
    problem.demonstration.push_back(std::move(d));
  }
  std::ostringstream comment;
  comment << "hbirl generate --domain " << args.domain << " --seed " << args.seed << ": the run its \"sensor\" section "
          << "simulates (what hbirl-sim-driver publishes for it): " << controlled
          << " trajectories of the controlled run (the subject alone, \"controlled\": true) and "
          << problem.demonstration.size() - static_cast<size_t>(controlled)
          << " demonstrations, each with its true steps.";
  nlohmann::ordered_json doc;
  doc["comment"] = comment.str();
  doc.update(problem_to_json(problem));
  emit(format_json(doc), args.out);
  return 0;
}

}  // namespace hbirl::cli
