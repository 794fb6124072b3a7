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
  std::string log, out, key_file, format;
  bool allow_incomplete = false;
  app::DomainArgs domain;
  app::LearnSettings settings;  // those that override the prior (app::Front::kPrior)
};

// A CSV field: quoted when it holds a comma, a quote or a line break.
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csv_number(double v) { return nlohmann::json(v).dump(); }  // the shortest that reads back exactly

// The demonstrations as CSV for pandas and spreadsheets: one row per observation
// (trajectory, step, symbol, eta per source, context), a row with empty symbol for a step
// without observations, and the true state and action when the run recorded them. The
// problem file (JSON) is the complete record; this is a view of its observations.
std::string observations_csv(const Problem& p, int num_sources, const std::vector<std::string>& source_names) {
  bool truth = false;
  for (const auto& t : p.demonstration) truth = truth || t.truth.has_value();
  std::string out = "trajectory,step";
  if (truth) out += ",state,action";
  out += ",symbol";
  for (int j = 0; j < num_sources; ++j) {
    const std::string name = static_cast<size_t>(j) < source_names.size()
                                 ? source_names[static_cast<size_t>(j)]
                                 : (j == 0 ? "subject" : "element " + std::to_string(j));
    out += "," + csv_field("eta " + name);
  }
  out += ",context\n";
  const auto name_of = [](const std::vector<std::string>& names, int i) {
    return static_cast<size_t>(i) < names.size() ? csv_field(names[static_cast<size_t>(i)]) : std::to_string(i);
  };
  for (size_t i = 0; i < p.demonstration.size(); ++i) {
    const DemonstratedTrajectory& d = p.demonstration[i];
    if (!d.steps) continue;
    const ObservedTrajectory& o = *d.steps;
    for (int t = 0; t < o.length(); ++t) {
      std::string lead = std::to_string(i) + "," + std::to_string(t);
      if (truth) {
        lead += d.truth ? "," + name_of(p.state_names, (*d.truth)[static_cast<size_t>(t)].state) + "," +
                              name_of(p.action_names, (*d.truth)[static_cast<size_t>(t)].action)
                        : ",,";
      }
      const int begin = o.step_begin[static_cast<size_t>(t)], end = o.step_begin[static_cast<size_t>(t) + 1];
      if (begin == end) out += lead + "," + std::string(static_cast<size_t>(num_sources) + 1, ',') + "\n";
      for (int m = begin; m < end; ++m) {
        out += lead + "," + std::to_string(o.symbols[static_cast<size_t>(m)]);
        for (int j = 0; j < num_sources; ++j) out += "," + (j < o.eta.cols() ? csv_number(o.eta(m, j)) : "");
        out += "," + (o.contexts.empty() ? std::string() : std::to_string(o.context(m))) + "\n";
      }
    }
  }
  return out;
}

// The run as a problem file (app/recorded_problem.hpp): learning it again starts where
// the live optimiser started.
int run_export(const ExportArgs& args) {
  const app::RecordedProblem r =
      app::read_recorded_problem({args.log, args.key_file, args.allow_incomplete},
                                 app::open_domain_args(args.domain, "hbirl"), args.settings, "hbirl export");
  // --format, else from --out's extension: a file named .csv gets CSV, not JSON.
  const bool csv = args.format.empty() ? args.out.size() >= 4 && args.out.compare(args.out.size() - 4, 4, ".csv") == 0
                                       : args.format == "csv";
  if (csv) {
    const int sources = r.problem.observation_model ? 1 + r.problem.observation_model->num_confounders : 1;
    emit(observations_csv(r.problem, sources, r.source_names), args.out);
    std::cerr << "hbirl export: " << r.problem.demonstration.size() << " demonstrations as CSV"
              << (args.out.empty() ? "" : " -> " + args.out) << "\n";
    return 0;
  }
  nlohmann::ordered_json comment;
  comment["comment"] =
      "Exported by hbirl export from " + args.log + " (domain " + r.domain +
      "): " + std::to_string(r.problem.demonstration.size()) + " demonstrations; the " +
      std::to_string(r.controlled_episodes) +
      " controlled-run episodes are in observation_model.subject_alpha (the prior the optimiser learned from)";
  emit_streamed([&](std::ostream& out) { write_problem(out, r.problem, {}, comment); }, args.out);
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
  cmd->add_option(
         "--format", args->format,
         "json: a problem file (everything: the MDP, the prior, the demonstrations); csv: the demonstrations'\n"
         "observations, one row each (trajectory, step, symbol, eta per source, context; the true state and\n"
         "action when recorded), for pandas. Default: csv when --out ends in .csv, else json")
      ->check(CLI::IsMember({"json", "csv"}));
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
