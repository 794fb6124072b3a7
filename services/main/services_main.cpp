// The service processes of the set (docs/services.md), one executable: it runs as the service it is
// called by -- hbirl-sim-driver, hbirl-perception, hbirl-labeller, hbirl-sampler,
// hbirl-optimiser are links to it -- or as `hbirl-services SERVICE ...`. Each process only
// wires a library service (services/*_service.hpp, sim_driver/simulator/simulator_service.hpp,
// services/optimiser.hpp) to the bus and to its command line.
#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <set>

#include "app/domain_args.hpp"
#include "learner/input_error.hpp"
#include "services/estep_service.hpp"
#include "services/keyed_bus.hpp"
#include "services/labeller_service.hpp"
#include "problem/json_format.hpp"
#include "services/learning.hpp"
#include "services/optimiser.hpp"
#include "services/perception_service.hpp"
#include "services/process.hpp"
#include "services/sampler_worker.hpp"
#include "sim_driver/onion/scene.hpp"
#include "sim_driver/simulator/simulator_service.hpp"

namespace hbirl::services {
namespace {

struct Common {
  std::string url;
  std::string id;
  std::string key_file;
  std::string alive_file;
  int restarts = 0;
};

void add_common(CLI::App& app, Common& c) {
  app::add_url_option(&app, c.url, "to use");
  app.add_option("--id", c.id, "This process's id in STATUS messages (default: service-host-pid)");
  app.add_option("--restarts", c.restarts,
                 "How many times the supervisor restarted this service before (shown in STATUS)")
      ->check(CLI::Range(0, 1000000));
  app::add_key_option(&app, c.key_file,
                      "sign every message for the run it names and drop, counting them, those not signed with it for\n"
                      "that run. Without it the bus is unauthenticated");
  app.add_option("--alive-file", c.alive_file,
                 "Touch this file once a second while the service beats its heartbeat or computes, so a supervisor\n"
                 "(services/launch.sh) sees one that is alive but silent -- stopped, or blocked -- and restarts it");
}

// The bus of a service, signed when it has a key; its heartbeats touch --alive-file.
std::unique_ptr<Bus> service_bus(const Common& c, Counters& counters, KeyUse use = KeyUse::kService) {
  if (!c.alive_file.empty()) set_alive_file(c.alive_file);
  return with_key(open_bus(c.url), c.key_file, counters, use);
}

// Handles the bus and beats the heart until asked to stop; then says what it did.
int serve(Bus& bus, Heartbeat& heartbeat, const Counters& counters) {
  heartbeat.tick("running", true);
  while (!stop_requested()) {
    if (bus.handle(100) < 0) break;
    heartbeat.tick("running");
  }
  heartbeat.tick("done", true);
  std::fprintf(stderr, "hbirl-%s: stopped; %lld messages in, %lld out, %lld bad, %lld gaps\n", counters.service.c_str(),
               static_cast<long long>(counters.messages_in), static_cast<long long>(counters.messages_out),
               static_cast<long long>(counters.bad_messages), static_cast<long long>(counters.gaps));
  return 0;
}

// hbirl-sim-driver's options for the onion scene's run (`config`: which confounding elements).
void add_onion_run_options(CLI::App& app, SimulationOptions& sim, std::string& config) {
  app.add_option("--config,-c", config,
                 "onion: scene, all, controlled, or a list of blue-shirt, other-onions, foreground, mirror")
      ->capture_default_str();
  app.add_option("--controlled-sorts", sim.controlled_sorts, "onion: sorts in the controlled run")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--sorts", sim.sorts, "onion: demonstrated sorts")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--width", sim.scene.width, "onion: frame width (height = 3/4)")
      ->check(CLI::Range(onion::camera_view().min_width, onion::camera_view().max_width))
      ->capture_default_str();
  app.add_option("--fps", sim.scene.fps, "onion: frames per simulated second")
      ->check(CLI::Range(1, 240))
      ->capture_default_str();
}

// ... and for a simulated sensor's run (the Gridworld's, a domain file's).
void add_sensor_run_options(CLI::App& app, SimulationOptions& sim, std::string& eta) {
  app.add_option("--confounders", sim.confounders, "gridworld: confounding elements |E|")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option("--per-step", sim.per_step, "gridworld: observations per step")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  app.add_option("--trajectories", sim.trajectories, "gridworld: demonstrations")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--controlled-trajectories", sim.controlled_trajectories,
                 "gridworld: trajectories of the controlled run")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--length", sim.length, "gridworld: steps per trajectory")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--eta", eta, "gridworld: the observations' eta, plausible, uniform or true")
      ->check(CLI::IsMember({"plausible", "uniform", "true"}))
      ->capture_default_str();
}

void apply_scene_and_eta(SimulationOptions& sim, const std::string& config, const std::string& eta) {
  const onion::SceneConfig elements = onion::SceneConfig::parse(config, "--config");
  sim.scene.blue_shirt_person = elements.blue_shirt_person;
  sim.scene.other_onions = elements.other_onions;
  sim.scene.foreground_person = elements.foreground_person;
  sim.scene.mirror = elements.mirror;
  sim.eta = eta == "uniform" ? EtaKind::kUniform : eta == "true" ? EtaKind::kTrue : EtaKind::kPlausible;
}

int sim_driver(int argc, char** argv) {
  CLI::App app(
      "hbirl-sim-driver: the simulator. Publishes a controlled run (no confounders, true states:\n"
      "the subject prior), then the demonstrations, as EPISODE markers and GROUND_TRUTH, and\n"
      "  onion:       CAMERA frames (PNG) of the onion-sorting scene, for perception and the labeller;\n"
      "  gridworld:   the paper's Gridworld (--size, default 5x5), whose simulated sensor publishes\n"
      "               OBSERVATIONS with their eta itself (no perception or labeller needed);\n"
      "  FILE.json:   a domain file's task, watched by the sensor its \"sensor\" section describes\n"
      "               (docs/your-task.md \"Your own task\"), publishing OBSERVATIONS the same way.\n"
      "Stays to publish lost frames again (FRAME_REQUEST) until the optimiser's REWARD.");
  Common c;
  add_common(app, c);
  SimulatorOptions o;
  SimulationOptions& sim = o.simulation;
  app::DomainArgs d{"onion", {}};
  std::string config = "all";
  std::string eta = "plausible";
  double delay = 10.0;
  bool print_listeners = false;
  app::add_domain_options(&app, d, "onion, gridworld or a domain file");
  app.add_flag("--print-listeners", print_listeners,
               "Print the services this domain's run needs listening (perception and labeller for a camera,\n"
               "the optimiser) and exit");
  app.add_option("--seed", sim.seed,
                 "Seed of the run (onion: sorts and scene; gridworld: goal, trajectories, observations;\n"
                 "a domain file: trajectories, observations)")
      ->capture_default_str();
  app.add_option("--max-frames-per-second", o.max_frames_per_second,
                 "Pacing in wall-clock frames (a sensor: steps) per second (0: none)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  app.add_option("--start-delay", delay,
                 "At most this many seconds to wait for the services downstream to be listening")
      ->check(CLI::Range(0.0, 600.0))
      ->capture_default_str();
  add_onion_run_options(app, sim, config);
  add_sensor_run_options(app, sim, eta);
  CLI11_PARSE(app, argc, argv);
  apply_scene_and_eta(sim, config, eta);
  const std::shared_ptr<const Domain> domain = app::open_domain_args(d, "hbirl");
  if (!domain) throw InputError("--domain", "give the domain to simulate: onion, gridworld or a domain file");
  if (print_listeners) {
    std::printf("%s\n", domain->has_camera() ? "perception labeller optimiser" : "optimiser");
    return 0;
  }
  Counters counters;
  counters.service = "sim_driver";
  counters.restarts = c.restarts;
  std::unique_ptr<Bus> bus = service_bus(c, counters);
  Heartbeat heartbeat(*bus, counters, "sim_driver", c.id.empty() ? default_id("sim_driver") : c.id);
  heartbeat.tick("starting", true);
  Simulator driver(*bus, *domain, o, counters);
  const bool finished = driver.serve(
      stop_requested, delay, [&heartbeat](const std::string& state) { heartbeat.tick(state); },
      [](const std::string& s) { std::fprintf(stderr, "hbirl-sim-driver: %s\n", s.c_str()); });
  heartbeat.tick(finished ? "done" : "stopped", true);
  std::fprintf(stderr, "hbirl-sim-driver: done; %lld frames sent again on request, %lld bad messages\n",
               static_cast<long long>(driver.frames_resent()), static_cast<long long>(counters.bad_messages));
  return 0;
}

int perception(int argc, char** argv) {
  CLI::App app("hbirl-perception: CAMERA frames -> colour blobs -> DETECTIONS (one message per frame).");
  Common c;
  add_common(app, c);
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);  // one core per process
  Counters counters;
  counters.service = "perception";
  counters.restarts = c.restarts;
  std::unique_ptr<Bus> bus = service_bus(c, counters);
  PerceptionService service(*bus, counters);
  Heartbeat heartbeat(*bus, counters, "perception", c.id.empty() ? default_id("perception") : c.id);
  return serve(*bus, heartbeat, counters);
}

int labeller(int argc, char** argv) {
  CLI::App app("hbirl-labeller: DETECTIONS -> the paper's observations with their eta -> OBSERVATIONS.");
  Common c;
  add_common(app, c);
  bool uniform = false;
  app::DomainArgs d{"onion", {}};
  app::add_domain_options(&app, d, "The domain whose camera's frames are labelled (its reference sizes)");
  app.add_flag("--uniform-eta", uniform, "Uniform eta instead of the paper's plausible rules");
  CLI11_PARSE(app, argc, argv);
  const std::shared_ptr<const Domain> domain = app::open_domain_args(d, "hbirl-labeller");
  if (!domain) throw InputError("--domain", "give the domain whose camera's frames are labelled (onion)");
  if (!domain->camera()) {
    throw InputError(
        "--domain",
        "'" + domain->name() + "' has no camera: its sensor publishes OBSERVATIONS itself, no labeller is needed");
  }
  Counters counters;
  counters.service = "labeller";
  counters.restarts = c.restarts;
  std::unique_ptr<Bus> bus = service_bus(c, counters);
  LabellerService service(*bus, counters, *domain->camera(), uniform);
  Heartbeat heartbeat(*bus, counters, "labeller", c.id.empty() ? default_id("labeller") : c.id);
  return serve(*bus, heartbeat, counters);
}

int sampler(int argc, char** argv) {
  CLI::App app(
      "hbirl-sampler: an E-step worker. Receives the optimiser's MDP (MDP) and, on a channel of its\n"
      "own (TRAJECTORY_<tag of its --id>), the trajectories of the blocks it is assigned -- its share\n"
      "only, once -- and answers ESTEP_REQUEST for those blocks (ESTEP_RESULT). It needs no domain:\n"
      "one worker serves any run. Run any number, on any number of machines (same LCM URL with ttl=1).\n"
      "With --key: a run's key file (OUT/run.key) serves that run only; a key for many runs (hbirl keygen\n"
      "FILE, the one given to services/launch.sh --key) serves every run of it, each answer signed for the\n"
      "run of its request.");
  Common c;
  add_common(app, c);
  std::int64_t die_after = -1;
  std::int64_t max_dataset_mb = SamplerWorker::kDefaultMaxDatasetBytes >> 20;
  app.add_option("--max-dataset-mb", max_dataset_mb,
                 "The most memory the blocks of trajectories this worker holds may take, in MB; a block that would\n"
                 "take more is refused (counted as bad) and its partial copy dropped, whatever a sender declares")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 20));
  bool lie = false;
  app.add_flag("--testing-lie", lie,
               "Testing: add 1 to the first count of every answer (a worker that lies, for the optimiser's\n"
               "spot check to catch)");
  app.add_option("--kill-self-after-blocks", die_after,
                 "Testing: SIGKILL this process once it has computed this many blocks (a worker dying mid-run)");
  CLI11_PARSE(app, argc, argv);
  Counters counters;
  counters.service = "sampler";
  counters.restarts = c.restarts;
  std::unique_ptr<Bus> bus = service_bus(c, counters, KeyUse::kWorker);  // a key file without a run: any run of the key
  SamplerWorker worker(*bus, c.id.empty() ? default_id("sampler") : c.id, counters, max_dataset_mb << 20);
  if (lie) worker.lie_for_testing();
  while (!stop_requested()) {
    if (worker.handle(100) < 0) break;
    if (die_after >= 0 && worker.blocks_computed() >= die_after) {
      std::fprintf(stderr, "hbirl-sampler: %s kills itself (SIGKILL) after %lld blocks, as asked\n",
                   worker.id().c_str(), static_cast<long long>(worker.blocks_computed()));
      std::raise(SIGKILL);
    }
  }
  worker.publish_status("done");
  std::fprintf(stderr, "hbirl-sampler: stopped (%s); %lld blocks computed, %lld messages in, %lld bad\n",
               worker.id().c_str(), static_cast<long long>(worker.blocks_computed()),
               static_cast<long long>(counters.messages_in), static_cast<long long>(counters.bad_messages));
  return 0;
}

// hbirl-optimiser's options for collecting the run and for its workers (the learning
// settings come from app/learn_settings.hpp).
void add_collection_options(CLI::App& app, OptimiserOptions& o, std::int64_t& max_dataset_mb, bool& no_spot_check) {
  app.add_option("--workers", o.workers, "Sampler workers to wait for before learning (0: compute here)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  app.add_option("--wait-workers-ms", o.wait_workers_ms, "How long to wait for them")->capture_default_str();
  app.add_option("--timeout-ms", o.executor.timeout_ms, "Wait this long for an E-step block before re-asking")
      ->check(CLI::Range(1, 3600000))
      ->capture_default_str();
  app.add_option("--resend-after-ms", o.resend_after_ms,
                 "After the end of the run, ask for lost frames again once none has come for this long")
      ->check(CLI::Range(1, 3600000))
      ->capture_default_str();
  app.add_flag("--allow-incomplete", o.allow_incomplete,
               "Learn from what came when frames stop coming before the run is complete (after --quiet-ms), and say\n"
               "what is missing in the result (\"incomplete\"). Without it such a run fails (exit 3) after\n"
               "--incomplete-after-ms without a frame, asking for the missing ones again all the while");
  app.add_option("--quiet-ms", o.quiet_ms,
                 "With --allow-incomplete: learn from what came once no frame has come for this long\n"
                 "after the end of the run")
      ->check(CLI::Range(1, 3600000))
      ->capture_default_str();
  app.add_option("--incomplete-after-ms", o.incomplete_after_ms,
                 "Without --allow-incomplete: fail the run once no frame has come for this long after its end")
      ->check(CLI::Range(1, 86400000))
      ->capture_default_str();
  app.add_flag("--anytime", o.anytime,
               "Publish an estimate (ESTIMATE) after each demonstration that ends with all its frames, learned\n"
               "here while the run goes on, EM also started from the previous estimate; with --posterior-samples N\n"
               "it carries the confidence (docs/MODEL.md \"Learning while it watches\")");
  app.add_option("--stop-at-confidence", o.stop_at_confidence,
                 "Knowing when it has seen enough: once --stop-after estimates in a row have a confidence >= p,\n"
                 "send STOP (the simulator or hbirl publish ends the run after the episode under way). Needs\n"
                 "--anytime (implied) and --posterior-samples");
  app.add_option("--stop-after", o.stop_after, "With --stop-at-confidence: estimates in a row at or above it")
      ->capture_default_str();
  app.add_flag("--same-numerics-only", o.executor.same_numerics_only,
               "Give work only to sampler workers whose floating-point results are this build's bit for bit (their\n"
               "numerics fingerprint): theta identical to a one-process run even when other builds or CPUs join");
  app.add_option("--max-dataset-mb", max_dataset_mb,
                 "The most memory the run's observations may take, in MB; frames beyond it are refused (counted as\n"
                 "bad), whatever a sender publishes")
      ->capture_default_str()
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 20));
  app.add_flag("--no-spot-check", no_spot_check,
               "Do not recompute one worker-computed block per E-step pass here (by default a worker whose block\n"
               "differs from the optimiser's own is reported, gets no more work, and its blocks are computed here)");
}

// --stop-at-confidence p and --stop-after k: p in (0, 1), k >= 1, the confidence drawn,
// estimates made (--anytime).
void check_stop_rule(const CLI::App& app, OptimiserOptions& o) {
  if (o.stop_after < 1 || o.stop_after > 1000000) throw InputError("--stop-after", "must be in [1, 1000000]");
  if (app.count("--stop-at-confidence") == 0) return;
  if (!(o.stop_at_confidence > 0.0 && o.stop_at_confidence < 1.0)) {
    throw InputError("--stop-at-confidence", "must be in (0, 1)");
  }
  if (o.learning.posterior.samples == 0) {
    throw InputError("--stop-at-confidence",
                     "needs --posterior-samples N: the confidence comes from N posterior draws");
  }
  o.anytime = true;
}

// What hbirl-optimiser prints (docs/services.md "Services and channels": the result JSON).
nlohmann::json result_json(const OptimiserResult& r, const OptimiserOptions& o, const Counters& counters) {
  nlohmann::json j;
  add_learned_run(j, r, o.domain);
  if (!r.incomplete.empty()) j["incomplete"] = r.incomplete;
  j["frame_requests"] = r.frame_requests;
  if (!r.recording.empty()) j["recording"] = r.recording;  // --recording: complete, or what it lacks
  if (o.anytime) {
    nlohmann::json confidence = nlohmann::json::array();
    for (const auto& e : r.estimates) confidence.push_back(e.confidence);
    j["estimates"] = {{"demonstrations", r.estimates.size()}, {"confidence", confidence}};
    if (r.stop_sent_after > 0) j["stop_sent_after"] = r.stop_sent_after;
  }
  j["workers"] = r.workers;                          // ready when learning began
  j["workers_answered"] = r.estep.blocks_by_worker;  // id -> E-step blocks it computed
  j["estep"] = {{"requests", r.estep.requests},
                {"remote_blocks", r.estep.remote_blocks},
                {"local_blocks", r.estep.local_blocks},
                {"retried_blocks", r.estep.retried_blocks},
                {"stale", r.estep.stale},
                {"duplicates", r.estep.duplicates},
                {"unassigned_answers", r.estep.unassigned},
                {"spot_checks", r.estep.spot_checks},
                {"workers_caught_lying", r.estep.liars},
                {"conflicting_answers", r.estep.conflicts},
                {"workers_with_other_numerics", r.estep.other_numerics},
                {"trial_passes", r.estep.trial_passes},
                {"round_trip_seconds", r.estep.round_trip_s}};
  j["bad_messages"] = counters.bad_messages;
  j["other_run_messages"] = counters.other_run;
  j["authenticated"] = counters.authenticated;
  j["gaps"] = counters.gaps;
  return j;
}

int optimiser(int argc, char** argv) {
  CLI::App app(
      "hbirl-optimiser: collects the run (EPISODE, OBSERVATIONS, GROUND_TRUTH), learns the reward\n"
      "with HiddenDataEM, the E-step on the sampler workers, and publishes EM_PROGRESS and REWARD.\n"
      "Prints the result as JSON and exits.");
  Common c;
  add_common(app, c);
  OptimiserOptions o;
  std::string out;
  app::DomainArgs d;
  app::add_domain_options(&app, d,
                          "The domain learned on: onion, gridworld or a domain file (default: the built-in domain\n"
                          "the EPISODE markers name; a domain file must be given here)");
  std::int64_t max_dataset_mb = o.max_dataset_bytes >> 20;
  bool no_spot_check = false;
  add_collection_options(app, o, max_dataset_mb, no_spot_check);
  app::add_learn_settings(&app, o.learning, app::Front::kOptimiser);
  app.add_option("--out", out, "Also write the result JSON to this file");
  app.add_option("--recording", o.recording.path,
                 "The run's lcm-logger recording (services/launch.sh --record): once the run is complete, wait\n"
                 "until the recording holds it too, asking again for what lcm-logger lost, so that hbirl learn\n"
                 "--log finds the whole run (read with --key, as its readers read it); after learning, publish\n"
                 "the REWARD again until the recording holds it (hbirl report: a finished run)");
  CLI11_PARSE(app, argc, argv);
  o.recording.key_file = c.key_file;
  o.executor.spot_check = !no_spot_check;
  o.max_dataset_bytes = max_dataset_mb << 20;
  check_stop_rule(app, o);
  if (!d.spec.empty()) o.domain = app::open_domain_args(d, "hbirl");
  Counters counters;
  counters.service = "optimiser";
  counters.restarts = c.restarts;
  std::unique_ptr<Bus> bus = service_bus(c, counters);
  Heartbeat heartbeat(*bus, counters, "optimiser", c.id.empty() ? default_id("optimiser") : c.id);
  o.beat = [&heartbeat](const std::string& state) { heartbeat.tick(state); };
  std::optional<OptimiserResult> result;
  try {
    result = run_optimiser(
        *bus, o, counters, stop_requested,
        [](const std::string& s) { std::fprintf(stderr, "hbirl-optimiser: %s\n", s.c_str()); },
        [&heartbeat] { heartbeat.tick("starting", true); });  // listening: the simulator may start
  } catch (const RunFailed& e) {
    // Not restarted by the supervisor (exit 3): collecting the run again would end the same way.
    heartbeat.tick("failed", true);
    std::fprintf(stderr, "hbirl-optimiser: the run failed: %s\n", e.what());
    return 3;
  }
  if (!result) {
    heartbeat.tick("stopped", true);
    std::fprintf(stderr, "hbirl-optimiser: stopped before the end of learning; %lld messages in, %lld bad, %lld gaps\n",
                 static_cast<long long>(counters.messages_in), static_cast<long long>(counters.bad_messages),
                 static_cast<long long>(counters.gaps));
    return 1;
  }
  const nlohmann::json j = result_json(*result, o, counters);
  std::cout << j.dump(2) << std::endl;
  if (!out.empty()) {
    std::ofstream file(out);
    file << j.dump(2) << "\n";
    if (!file) throw InputError("--out", "cannot write " + out);
  }
  heartbeat.tick("done", true);
  return 0;
}

const std::map<std::string, int (*)(int, char**)>& services() {
  static const std::map<std::string, int (*)(int, char**)> s = {{"sim-driver", sim_driver},
                                                                {"perception", perception},
                                                                {"labeller", labeller},
                                                                {"sampler", sampler},
                                                                {"optimiser", optimiser}};
  return s;
}

}  // namespace
}  // namespace hbirl::services

int main(int argc, char** argv) {
  using namespace hbirl::services;
  install_stop_handlers();
  std::string name = std::filesystem::path(argv[0]).filename().string();
  if (name.rfind("hbirl-", 0) == 0) name = name.substr(6);
  if (name == "services") {
    if (argc < 2 || !services().count(argv[1])) {
      std::fprintf(
          stderr,
          "usage: hbirl-services SERVICE [OPTIONS]   SERVICE: sim-driver, perception, labeller, sampler, optimiser\n");
      return 2;
    }
    name = argv[1];
    --argc;
    ++argv;
  }
  const auto it = services().find(name);
  if (it == services().end()) {
    std::fprintf(stderr, "hbirl-services: called as '%s', which is not a service\n", name.c_str());
    return 2;
  }
  try {
    return it->second(argc, argv);
  } catch (const hbirl::InputError& e) {
    std::fprintf(stderr, "hbirl-%s: %s\n", name.c_str(), e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hbirl-%s: internal error: %s\n", name.c_str(), e.what());
    return 1;
  }
}
