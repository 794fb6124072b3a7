// The E-step over the bus (docs/BENCHMARKS.md has the figures and the commands): one pass
// of the E-step computed here, and farmed out to 1, 2 and 4 sampler workers (threads with
// their own in-memory bus endpoints: the protocol's real code path, without the network),
// on the paper's Gridworld with 64 trajectories (4 blocks); and farmed out over LCM on
// loopback to 1-8 hbirl-sampler processes (BM_EStepPassOverLcm: run it inside a private
// network namespace, bench/in_netns.sh).
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <atomic>
#include <map>
#include <mutex>
#include <thread>

#include "services/estep_service.hpp"
#include "services/keyed_bus.hpp"
#include "services/lcm_bus.hpp"
#include "services/memory_bus.hpp"
#include "services/sampler_worker.hpp"
#include "sim_driver/gridworld/gridworld.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace hbirl::services {
namespace {

struct Data {
  GridworldTask task;
  std::vector<ObservedTrajectory> observed;
  ObservationPrior prior;
};

Data make_data(int trajectories) {
  Rng rng(1);
  Data out{make_gridworld_task({}, trajectories, 10, rng), {}, {}};
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
}

const Data& data() {
  static const Data d = make_data(64);
  return d;
}

// The data of the process benchmarks: 1,024 trajectories (64 blocks), 10 steps, 40
// observations per step.
const Data& large_data() {
  static const Data d = make_data(1024);
  return d;
}

// One pass here, on one thread: the compute the workers share. Argument: 0 the 64
// trajectories, 1 the 1,024.
void BM_EStepPassHere(benchmark::State& state) {
  const Data& d = state.range(0) == 0 ? data() : large_data();
  const ObservationEStep estep(d.task.mdp, d.observed, d.prior);
  const SoftSolution policy = soft_value_iteration(d.task.mdp, d.task.mdp.features * d.task.true_weights);
  const ObservationModel model = dirichlet_mean(d.prior);
  for (auto _ : state) benchmark::DoNotOptimize(estep.statistics(policy, model, 1).log_likelihood);
  state.counters["blocks"] = estep.num_blocks();
}
BENCHMARK(BM_EStepPassHere)->Arg(0)->Arg(1)->ArgName("large")->Unit(benchmark::kMillisecond)->UseRealTime();

// An E-step whose blocks go to `workers` sampler workers over `bus`, and a pass's inputs.
struct PassOverBus {
  std::shared_ptr<BusBlockExecutor> executor;
  std::unique_ptr<ObservationEStep> estep;
  SoftSolution policy;
  ObservationModel model;
};

PassOverBus pass_over_bus(Bus& bus, Counters& counters, const Data& d, const BusExecutorOptions& options, int workers,
                          int wait_ms, benchmark::State& state) {
  PassOverBus p;
  p.executor = std::make_shared<BusBlockExecutor>(bus, d.task.mdp, "gridworld", counters, options);
  if (p.executor->wait_for_workers(workers, wait_ms) != workers) {
    state.SkipWithError("workers did not come up (over LCM: inside a network namespace? bench/in_netns.sh)");
  }
  ObservationEStepOptions estep_options;
  estep_options.executor = p.executor;
  p.estep = std::make_unique<ObservationEStep>(d.task.mdp, d.observed, d.prior, estep_options);
  p.policy = soft_value_iteration(d.task.mdp, d.task.mdp.features * d.task.true_weights);
  p.model = dirichlet_mean(d.prior);
  return p;
}

// Counts the bytes on every channel of an LCM bus, from a thread of its own.
class BusSpy {
 public:
  explicit BusSpy(const std::string& url) : bus_(open_bus(url)) {
    bus_->subscribe(
        ".*",
        [this](const Message& m) {
          const std::lock_guard<std::mutex> lock(mutex_);
          bytes_[m.channel] += m.size;
        },
        100000);
    thread_ = std::thread([this] {
      while (!stop_) bus_->handle(10);
    });
  }
  ~BusSpy() {
    stop_ = true;
    thread_.join();
  }
  std::map<std::string, std::int64_t> take() {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // what is in flight
    const std::lock_guard<std::mutex> lock(mutex_);
    return std::exchange(bytes_, {});
  }

 private:
  std::unique_ptr<Bus> bus_;
  std::mutex mutex_;
  std::map<std::string, std::int64_t> bytes_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// One pass farmed out over LCM (loopback multicast) to `workers` hbirl-sampler processes:
// the real processes, sockets and protocol. The first pass, which sends every worker its
// share of the trajectories, is timed apart (first_pass_ms, share_MB; worker_share_min and
// _max: the smallest and largest part of those bytes one worker's channel carried); the timed passes
// send requests and answers only (bus_kB_per_pass: every byte on the bus, heartbeats
// included). No spot check: the protocol's cost alone. On 2 cores more than 2 workers
// cannot compute faster: compare with BM_EStepPassHere/large:1 for the overhead per block.
void BM_EStepPassOverLcm(benchmark::State& state) {
  const Data& d = large_data();
  const int n = static_cast<int>(state.range(0));
  const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152";
  const std::string sampler = std::string(HBIRL_BINARY_DIR) + "/hbirl-sampler";
  std::vector<pid_t> pids;
  for (int w = 0; w < n; ++w) {
    const std::string id = "bench-sampler-" + std::to_string(w);
    std::vector<std::string> args = {sampler, "--url", url, "--id", id};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t quiet;
    posix_spawn_file_actions_init(&quiet);
    posix_spawn_file_actions_addopen(&quiet, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid = 0;
    if (posix_spawn(&pid, sampler.c_str(), &quiet, nullptr, argv.data(), environ) == 0) pids.push_back(pid);
    posix_spawn_file_actions_destroy(&quiet);
  }
  {
    BusSpy spy(url);
    Counters c;
    c.quiet = true;
    std::unique_ptr<Bus> bus = open_bus(url);
    BusExecutorOptions executor_options;
    executor_options.spot_check = false;
    executor_options.timeout_ms = 10000;
    const PassOverBus pass = pass_over_bus(*bus, c, d, executor_options, n, 20000, state);
    const auto& [executor, estep, policy, model] = pass;
    const auto start = std::chrono::steady_clock::now();
    estep->statistics(policy, model, 1);
    state.counters["first_pass_ms"] =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    state.counters["share_MB"] = static_cast<double>(executor->stats().bytes_sent) / 1e6;
    // What each worker's channel carried in that first pass, as a share of all the
    // trajectories sent: its share of the data set (1 / workers when even).
    double smallest = 1.0, largest = 0.0;
    const auto first = spy.take();
    for (int w = 0; w < n; ++w) {
      const auto it = first.find(channels::trajectory_channel("bench-sampler-" + std::to_string(w)).name);
      const double share =
          it == first.end() ? 0.0 : static_cast<double>(it->second) / static_cast<double>(executor->stats().bytes_sent);
      smallest = std::min(smallest, share);
      largest = std::max(largest, share);
    }
    state.counters["worker_share_min"] = smallest;
    state.counters["worker_share_max"] = largest;
    std::int64_t passes = 0;
    for (auto _ : state) {
      benchmark::DoNotOptimize(estep->statistics(policy, model, 1).log_likelihood);
      ++passes;
    }
    std::int64_t total = 0;
    for (const auto& [channel, bytes] : spy.take()) {
      total += bytes;
      if (channel == "ESTEP_REQUEST" || channel == "ESTEP_RESULT") {
        state.counters[channel + "_kB"] = static_cast<double>(bytes) / 1e3 / static_cast<double>(passes);
      }
    }
    state.counters["bus_kB_per_pass"] = static_cast<double>(total) / 1e3 / static_cast<double>(passes);
    const auto s = executor->stats();
    state.counters["local_blocks"] = static_cast<double>(s.local_blocks);
    state.counters["retried"] = static_cast<double>(s.retried_blocks);
  }
  for (pid_t pid : pids) kill(pid, SIGTERM);
  for (pid_t pid : pids) waitpid(pid, nullptr, 0);
}
BENCHMARK(BM_EStepPassOverLcm)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->ArgName("workers")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

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
  const PassOverBus pass = pass_over_bus(*bus, c, d, executor_options, n, 10000, state);
  for (auto _ : state) benchmark::DoNotOptimize(pass.estep->statistics(pass.policy, pass.model, 1).log_likelihood);
  stop = true;
  for (auto& t : threads) t.join();
  const auto s = pass.executor->stats();
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
