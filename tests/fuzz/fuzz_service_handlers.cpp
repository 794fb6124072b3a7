// libFuzzer target: every service's message handlers, as a bus delivers to them. The
// input is a sequence of bus messages (fuzz_common.hpp's framing: a channel byte, a
// 2-byte size, the bytes), published on an in-process bus that every service listens
// on, built fresh for each input so a finding replays from its input alone:
//   SamplerWorker      MDP, TRAJECTORY_<tag>, ESTEP_REQUEST (and the MdpAssembler behind MDP)
//   DatasetBuilder     EPISODE, OBSERVATIONS, GROUND_TRUTH (twice: any domain, and
//                      expecting the simulated one's shape, as the optimiser does)
//   PerceptionService  CAMERA (PNG and JPEG frames; fuzz_png_frame.cpp goes deeper)
//   LabellerService    DETECTIONS
//   Simulator          FRAME_REQUEST (a small simulated gridworld run)
//   BusBlockExecutor   STATUS, ESTEP_RESULT (the optimiser's side of the E-step)
//   DashboardState     everything the page shows
//   KeyedBus           every message, checked against a run key: no input can carry a
//                      valid tag, so its handler must never run
// What the services publish in answer goes round the same bus (perception's DETECTIONS
// reach the labeller, whose OBSERVATIONS reach the data set and the dashboard). A
// refused message is counted (Counters) and dropped; only crashes, sanitizer reports,
// timeouts and huge allocations are findings.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dashboard/state.hpp"
#include "fuzz_common.hpp"
#include "services/dataset.hpp"
#include "services/estep_service.hpp"
#include "services/keyed_bus.hpp"
#include "services/labeller_service.hpp"
#include "services/memory_bus.hpp"
#include "services/perception_service.hpp"
#include "services/sampler_worker.hpp"
#include "sim_driver/simulator/simulator_service.hpp"
#include "sim_driver/registry/domain.hpp"

namespace {

using namespace hbirl;
using namespace hbirl::services;

// The simulator's run, planned once (planning it takes half of an input's time): each
// input's Simulator gets its own copy of the plan, with the frames made by the original.
class SharedRun final : public Simulation {
 public:
  explicit SharedRun(const Simulation& run) : run_(run) {
    episodes = run.episodes;
    frames_per_step = run.frames_per_step;
    step_seconds = run.step_seconds;
    true_weights = run.true_weights;
    num_symbols = run.num_symbols;
    num_sources = run.num_sources;
  }
  bool camera() const override { return run_.camera(); }
  double render(int id, int t, int k, cv::Mat& frame) const override { return run_.render(id, t, k, frame); }
  const ObservedTrajectory& observed(int id) const override { return run_.observed(id); }

 private:
  const Simulation& run_;
};

// What every input shares, built once: the simulated domain and its run, and a run key.
struct World {
  std::unique_ptr<Domain> domain;
  SimulatorOptions sim;
  std::unique_ptr<Simulation> run;
  RunKey key = RunKey::generate();

  World() {
    DomainOptions options;
    options.gridworld_size = 3;
    domain = open_domain("gridworld", options);
    sim.simulation.seed = 1;
    sim.simulation.trajectories = 2;
    sim.simulation.controlled_trajectories = 1;
    sim.simulation.length = 3;
    sim.simulation.per_step = 4;
    sim.simulation.confounders = 1;
    sim.max_frames_per_second = 0;
    run = domain->simulate(sim.simulation);
  }
};

const World& world() {
  static const World w;
  return w;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const World& w = world();
  const std::vector<fuzz::Record> records = fuzz::split_records(data, size);

  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub);
  Counters counters;
  counters.service = "fuzz";
  counters.quiet = true;
  // The most a sampler may hold while a data set arrives: far below -malloc_limit_mb.
  SamplerWorker worker(bus, fuzz::kFuzzSampler, counters, std::int64_t{64} << 20);
  DatasetBuilder any_domain;
  any_domain.subscribe(bus, counters);
  DatasetBuilder expecting;
  const Mdp& mdp = w.domain->mdp();
  expecting.expect(w.domain->name(), 4, 2, mdp.num_states, mdp.num_actions);
  expecting.subscribe(bus, counters);
  PerceptionService perception(bus, counters);
  LabellerService labeller(bus, counters, *builtin_domain("onion")->camera());
  Simulator driver(bus, w.domain->name(), std::make_unique<SharedRun>(*w.run), w.sim, counters);
  BusExecutorOptions executor_options;
  executor_options.timeout_ms = 0;
  BusBlockExecutor executor(bus, mdp, w.domain->name(), counters, executor_options);
  dashboard::DashboardState dashboard;
  dashboard.subscribe(bus, counters);
  KeyedBus keyed(std::make_unique<MemoryBus>(hub), w.key, counters);
  keyed.subscribe(".*", [](const Message&) { __builtin_trap(); });  // a forged tag passed

  for (const fuzz::Record& r : records) {
    bus.publish(fuzz::channel(r.channel), r.data, r.size);
    // The message, then what the services said to it, then what was said to that...
    // (bounded: a reply loop would be a finding of its own, as a timeout).
    for (int round = 0; round < 16 && bus.handle(0) > 0; ++round) {
    }
    keyed.handle(0);
    // What the optimiser and the page ask between messages.
    for (DatasetBuilder* d : {&any_domain, &expecting}) {
      d->complete();
      d->missing_frame_keys(8);
    }
  }
  worker.publish_status("running");  // its digests, to the optimiser's side
  bus.handle(0);
  for (DatasetBuilder* d : {&any_domain, &expecting}) {
    d->missing_frames();
    d->missing_truth();
    d->unfinished_episodes();
    if (d->run_ended()) d->build();
  }
  dashboard.json(0).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  dashboard.frame_png();
  return 0;
}
