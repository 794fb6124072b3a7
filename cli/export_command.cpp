// hbirl export: a recorded run of the service set as a problem file.
#include <iostream>
#include <memory>

#include "app/domain_args.hpp"
#include "commands.hpp"
#include "full_commands.hpp"
#include "problem/json_format.hpp"
#include "app/recorded_problem.hpp"

namespace hbirl::cli {

namespace {

struct ExportArgs {
  std::string log, out, key_file;
  bool allow_incomplete = false;
  app::DomainArgs domain;
  app::LearnSettings settings;  // those that override the prior (app::Front::kPrior)
};

// The run as a problem file (app/recorded_problem.hpp): learning it again starts where
// the live optimiser started.
int run_export(const ExportArgs& args) {
  const app::RecordedProblem r =
      app::read_recorded_problem({args.log, args.key_file, args.allow_incomplete},
                                 app::open_domain_args(args.domain, "hbirl"), args.settings, "hbirl export");
  nlohmann::ordered_json doc = problem_to_json(r.problem);
  doc["comment"] =
      "Exported by hbirl export from " + args.log + " (domain " + r.domain +
      "): " + std::to_string(r.problem.demonstration.size()) + " demonstrations; the " +
      std::to_string(r.controlled_episodes) +
      " controlled-run episodes are in observation_model.subject_alpha (the prior the optimiser learned from)";
  emit(format_json(doc), args.out);
  std::cerr << "hbirl export: " << r.problem.demonstration.size() << " demonstrations, " << r.controlled_episodes
            << " controlled episodes (in the prior), " << r.missing_frames << " frames missing, " << r.bad_messages
            << " bad messages" << (args.out.empty() ? "" : " -> " + args.out) << "\n";
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
