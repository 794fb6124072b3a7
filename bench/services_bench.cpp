// The E-step over the bus (docs/BENCHMARKS.md has the figures and the command): one pass
// of the E-step computed here, and farmed out to 1, 2 and 4 sampler workers (threads with
// their own in-memory bus endpoints: the protocol's real code path, without the network),
// on the paper's Gridworld with 64 trajectories (4 blocks).
#include <benchmark/benchmark.h>

#include <atomic>
#include <thread>

#include "services/estep_service.hpp"
#include "services/keyed_bus.hpp"
#include "services/memory_bus.hpp"
#include "services/sampler_worker.hpp"
#include "sim_driver/gridworld.hpp"
#include "sim_driver/gridworld_observations.hpp"

namespace hbirl::services {
namespace {

struct Data {
  GridworldTask task;
  std::vector<ObservedTrajectory> observed;
  ObservationPrior prior;
};

const Data& data() {
  static const Data d = [] {
    Rng rng(1);
    Data out{make_gridworld_task({}, 64, 10, rng), {}, {}};
    GridworldObservationOptions options;  // 40 observations per step, 3 confounders, plausible eta
    out.observed = observe_gridworld(out.task.mdp, out.task.trajectories, gridworld_subject_observation_model(5, 1.0),
                                     random_confounder_observation_model(3, rng), options, rng)
                       .trajectories;
    out.prior.num_symbols = 4;
    out.prior.num_confounders = 3;
    out.prior.subject_alpha = Eigen::MatrixXd::Ones(out.task.mdp.num_pairs(), 4);
    out.prior.confounder_alpha = Eigen::MatrixXd::Ones(3, 4);
    out.prior.learn_eta = false;  // eta as stated: the pass's cost without the contexts' counts
    return out;
  }();
  return d;
}

void BM_EStepPassHere(benchmark::State& state) {
  const Data& d = data();
  const ObservationEStep estep(d.task.mdp, d.observed, d.prior);
  const SoftSolution policy = soft_value_iteration(d.task.mdp, d.task.mdp.features * d.task.true_weights);
  const ObservationModel model = dirichlet_mean(d.prior);
  for (auto _ : state) benchmark::DoNotOptimize(estep.statistics(policy, model, 1).log_likelihood);
}
BENCHMARK(BM_EStepPassHere)->Unit(benchmark::kMillisecond)->UseRealTime();

// Arguments: workers; then 0: as before issue 14 (no spot check, no key), 1: the default
// (the optimiser spot-checks one block per pass), 2: the default with every message signed
// and checked with a run key (docs/RELIABILITY.md).
void BM_EStepPassOverBus(benchmark::State& state) {
  const Data& d = data();
  auto hub = std::make_shared<MemoryHub>();
  const int n = static_cast<int>(state.range(0));
  const int mode = static_cast<int>(state.range(1));
  const RunKey key = RunKey::generate();
  std::atomic<bool> stop{false};
  std::vector<std::thread> threads;
  std::vector<std::unique_ptr<Counters>> counters;
  std::vector<std::unique_ptr<Bus>> buses;
  std::vector<std::unique_ptr<SamplerWorker>> workers;
  const auto endpoint = [&](Counters& c) -> std::unique_ptr<Bus> {
    if (mode < 2) return std::make_unique<MemoryBus>(hub);
    return std::make_unique<KeyedBus>(std::make_unique<MemoryBus>(hub), key, c);
  };
  for (int w = 0; w < n; ++w) {
    counters.push_back(std::make_unique<Counters>());
    counters.back()->quiet = true;
    buses.push_back(endpoint(*counters.back()));
    workers.push_back(std::make_unique<SamplerWorker>(*buses.back(), "sampler-" + std::to_string(w), *counters.back()));
  }
  for (int w = 0; w < n; ++w) {
    threads.emplace_back([&, w] {
      while (!stop) workers[static_cast<size_t>(w)]->handle(5);
    });
  }
  Counters c;
  c.quiet = true;
  std::unique_ptr<Bus> bus = endpoint(c);
  BusExecutorOptions executor_options;
  executor_options.spot_check = mode >= 1;
  auto executor = std::make_shared<BusBlockExecutor>(*bus, d.task.mdp, "gridworld", c, executor_options);
  if (executor->wait_for_workers(n, 10000) != n) state.SkipWithError("workers did not come up");
  ObservationEStepOptions options;
  options.executor = executor;
  const ObservationEStep estep(d.task.mdp, d.observed, d.prior, options);
  const SoftSolution policy = soft_value_iteration(d.task.mdp, d.task.mdp.features * d.task.true_weights);
  const ObservationModel model = dirichlet_mean(d.prior);
  for (auto _ : state) benchmark::DoNotOptimize(estep.statistics(policy, model, 1).log_likelihood);
  stop = true;
  for (auto& t : threads) t.join();
  const auto s = executor->stats();
  state.counters["local_blocks"] = static_cast<double>(s.local_blocks);
  state.counters["retried"] = static_cast<double>(s.retried_blocks);
}
BENCHMARK(BM_EStepPassOverBus)
    ->ArgsProduct({{1, 2, 4}, {0, 1, 2}})
    ->ArgNames({"workers", "mode"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace hbirl::services
