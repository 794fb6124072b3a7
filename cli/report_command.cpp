// hbirl report: the dashboard's views of a finished run, as a static page.
#include <iostream>
#include <memory>

#include "app/domain_args.hpp"
#include "commands.hpp"
#include "full_commands.hpp"
#include "dashboard/report.hpp"

namespace hbirl::cli {

Command add_report(CLI::App& app) {
  struct Args {
    std::string log, out, key_file;
    app::DomainArgs domain;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(kReport.name, kReport.description);
  cmd->add_option("--log", args->log, "The run's LCM log (lcm-logger)")->required();
  cmd->add_option("--out", args->out, "Folder to write the report to (created)")->required();
  app::add_domain_options(cmd, args->domain,
                          "The run's domain file, when it ran on one (built-in domains are named by the run)");
  app::add_key_option(cmd, args->key_file, app::kRecordingKeyHelp);
  return [args] {
    const dashboard::Report r =
        dashboard::write_report(args->log, args->out, app::open_domain_args(args->domain, "hbirl"), args->key_file);
    for (const auto& p : r.problems) std::cerr << "hbirl: warning: figure not drawn: " << p << "\n";
    std::cout << r.page << "\n";
    std::cerr << "hbirl: report of " << r.messages << " messages (" << r.bad_messages << " bad), " << r.figures.size()
              << " figures: " << r.page << "\n";
    if (!r.finished) {  // a report, but not of a learned run: not a success
      std::cerr << "hbirl: the run in " << args->log
                << " never finished learning (no final REWARD): the report shows what was recorded\n";
      return 1;
    }
    return 0;
  };
}

}  // namespace hbirl::cli
