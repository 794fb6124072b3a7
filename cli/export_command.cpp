// hbirl export: a recorded run of the service set as a problem file.
#include <iostream>
#include <memory>

#include "app/domain_args.hpp"
#include "commands.hpp"
#include "full_commands.hpp"
#include "problem/json_format.hpp"
#include "services/optimiser.hpp"

namespace hbirl::cli {

namespace {

struct ExportArgs {
  std::string log, out, key_file;
  bool allow_incomplete = false;
  app::DomainArgs domain;
  app::LearnSettings settings;  // those that override the prior (app::Front::kPrior)
};

// The domain and the data set as the live optimiser had them; the observation model is
// the prior it learned from (the controlled run's counts included), so learning the file
// again starts where the optimiser started.
int run_export(const ExportArgs& args) {
  services::Counters counters;
  counters.service = "hbirl export";
  counters.quiet = true;
  const services::OptimiserResult r =
      services::collect_from_log({args.log, args.key_file, args.allow_incomplete}, counters);
  const std::shared_ptr<const Domain> domain = services::domain_of(r.data, app::open_domain_args(args.domain, "hbirl"));
  if (r.data.observed.empty()) throw InputError(args.log, "the log holds no demonstrations");
  Problem problem;
  problem.mdp = domain->mdp();
  const DomainNames names = domain->names(r.data.num_sources);
  problem.state_names = names.states;
  problem.action_names = names.actions;
  problem.feature_names = names.features;
  problem.observation_model = services::observation_prior(*domain, r.data);
  app::apply_to_prior(args.settings, *problem.observation_model);
  for (size_t i = 0; i < r.data.observed.size(); ++i) {
    DemonstratedTrajectory t;
    t.steps = r.data.observed[i];
    t.ends_in_terminal = r.data.observed[i].ends_in_terminal;
    if (i < r.data.truth.size() && r.data.truth[i].size() == static_cast<size_t>(r.data.observed[i].length())) {
      t.truth = r.data.truth[i];
    }
    problem.demonstration.push_back(std::move(t));
  }
  problem.true_weights = services::true_weights_of(*domain, r.data);
  nlohmann::ordered_json doc = problem_to_json(problem);
  doc["comment"] =
      "Exported by hbirl export from " + args.log + " (domain " + domain->name() +
      "): " + std::to_string(problem.demonstration.size()) + " demonstrations; the " +
      std::to_string(r.data.controlled_observed.size()) +
      " controlled-run episodes are in observation_model.subject_alpha (the prior the optimiser learned from)";
  emit(format_json(doc), args.out);
  std::cerr << "hbirl export: " << problem.demonstration.size() << " demonstrations, "
            << r.data.controlled_observed.size() << " controlled episodes (in the prior), " << r.missing_frames
            << " frames missing, " << counters.bad_messages << " bad messages"
            << (args.out.empty() ? "" : " -> " + args.out) << "\n";
  return 0;
}

}  // namespace

Command add_export(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand(kExport.name, kExport.description);
  cmd->add_option("--log", args->log, "The run's LCM log (lcm-logger)")->required();
  cmd->add_option("--out,-o", args->out, "Problem file to write (default: stdout)");
  app::add_domain_options(cmd, args->domain,
                          "The run's domain file, when it ran on one (built-in domains are named by the run)");
  app::add_key_option(cmd, args->key_file, app::kRecordingKeyHelp);
  cmd->add_flag("--allow-incomplete", args->allow_incomplete,
                "Export a recording whose run never reached its end (END_RUN): the episodes that finished");
  // As the run's hbirl-optimiser was told, when it was: the prior it learned from.
  app::add_learn_settings(cmd, args->settings, app::Front::kPrior);
  return [args] { return run_export(*args); };
}

}  // namespace hbirl::cli
