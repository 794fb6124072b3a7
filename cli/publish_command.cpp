// hbirl publish: a problem file's demonstration streamed onto the bus as a sensor would.
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "full_commands.hpp"
#include "problem/domain_file.hpp"
#include "services/keyed_bus.hpp"
#include "services/process.hpp"
#include "sim_driver/simulator/simulator_service.hpp"
#include "sim_driver/file/recorded_run.hpp"

namespace hbirl::cli {

namespace {

struct PublishArgs {
  std::string problem;
  std::string name;
  std::string url;
  std::string key_file;
  double rate = 100.0;
  double start_delay = 10.0;
  double linger = 600.0;
};

int run_publish(const PublishArgs& args) {
  const Problem problem = load_problem(args.problem);
  // The markers carry the name the optimiser knows the domain by: --name, else the file's
  // "name", else its stem. The optimiser refuses every episode of another name.
  const std::string name = !args.name.empty()      ? args.name
                           : !problem.name.empty() ? problem.name
                                                   : stem_name(args.problem);
  if (const std::string wrong = domain_name_problem(name); !wrong.empty())
    throw InputError(args.name.empty() ? "--problem" : "--name", "the domain name '" + name + "' " + wrong);
  std::unique_ptr<Simulation> run;
  try {
    run = recorded_run(problem);
  } catch (const InputError& e) {
    throw in_file(args.problem, e);
  }
  int controlled = 0, steps = 0;
  for (const auto& e : run->episodes) {
    controlled += e.controlled;
    steps += static_cast<int>(e.steps.size());
  }
  services::install_stop_handlers();
  services::Counters counters;
  counters.service = "publish";
  std::unique_ptr<services::Bus> bus = services::with_key(services::open_bus(args.url), args.key_file, counters);
  services::Heartbeat heartbeat(*bus, counters, "publish", services::default_id("publish"));
  SimulatorOptions options;
  options.max_frames_per_second = args.rate;  // one frame per step
  Simulator driver(*bus, name, std::move(run), options, counters);
  std::cerr << "hbirl publish: " << name << ": " << problem.demonstration.size() << " trajectories (" << controlled
            << " controlled), " << steps << " steps, to " << (args.url.empty() ? "LCM's default URL" : args.url)
            << "\n";
  // After the run: frames and end markers asked for again and END_RUN repeated, until
  // the optimiser's reward or --linger seconds.
  std::optional<std::chrono::steady_clock::time_point> published;
  const auto stop = [&] {
    return services::stop_requested() ||
           (published && std::chrono::steady_clock::now() - *published > std::chrono::duration<double>(args.linger));
  };
  const bool finished = driver.serve(
      stop, args.start_delay, [&heartbeat](const std::string& state) { heartbeat.tick(state); },
      [&](const std::string& s) {
        if (s.rfind("run published", 0) == 0) published = std::chrono::steady_clock::now();
        std::cerr << "hbirl publish: " << s << "\n";
      });
  heartbeat.tick(finished ? "done" : "stopped", true);
  std::cerr << "hbirl publish: " << (finished ? "done" : "stopped") << "; " << driver.frames_resent()
            << " steps sent again on request, " << counters.bad_messages << " bad messages\n";
  return finished ? 0 : 1;
}

}  // namespace

Command add_publish(CLI::App& app) {
  auto args = std::make_shared<PublishArgs>();
  CLI::App* cmd = app.add_subcommand(kPublish.name, kPublish.description);
  cmd->add_option("--problem,-p", args->problem, "Problem file (JSON, docs/files.md \"Problem files\")")->required();
  cmd->add_option(
      "--name", args->name,
      "The domain's name the episodes carry: the optimiser's (launch.sh --domain F: F's \"name\", else its\n"
      "stem). Default: the problem file's \"name\", else its stem");
  cmd->add_option("--url", args->url, "LCM URL (default: LCM's)");
  cmd->add_option("--key", args->key_file,
                  "The run's key file (services/launch.sh --key writes OUT/run.key): sign every message for its run,\n"
                  "as the services started with the same --key expect (docs/RELIABILITY.md)");
  cmd->add_option("--rate", args->rate, "Steps per second, wall clock (0: as fast as the bus takes them)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  cmd->add_option("--start-delay", args->start_delay, "At most this many seconds to wait for the optimiser's heartbeat")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  cmd->add_option("--linger", args->linger, "After publishing, wait at most this many seconds for the reward")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  return [args] { return run_publish(*args); };
}

}  // namespace hbirl::cli
