#include "services/estep_service.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sys/resource.h>

#include "expect_refused.hpp"
#include "learner/input_error.hpp"

#include <atomic>
#include <numeric>
#include <thread>

#include "learner/hidden_data_em.hpp"
#include "learner/soft_value_iteration.hpp"
#include "services/keyed_bus.hpp"
#include "services/memory_bus.hpp"
#include "services/sampler_worker.hpp"
#include "service_threads.hpp"
#include "sim_driver/gridworld/gridworld.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace hbirl::services {
namespace {

using testing::quiet;

// Workers on the task's MDP.
struct TaskWorker : testing::WorkerThread {
  TaskWorker(std::shared_ptr<MemoryHub> hub, const std::string& id, std::int64_t die_after = -1, bool lying = false);
};

// 40 trajectories (3 blocks of the E-step's sum) of the paper's Gridworld with three
// confounding elements and plausible eta.
struct Task {
  GridworldTask task;
  std::vector<ObservedTrajectory> observed;
  ObservationPrior prior;
};

const Task& task() {
  static const Task t = [] {
    Rng rng(5);
    Task out{make_gridworld_task({}, 40, 10, rng), {}, {}};
    const Eigen::MatrixXd subject = gridworld_subject_observation_model(5, 1.0);
    const Eigen::MatrixXd elements = random_confounder_observation_model(3, rng);
    GridworldObservationOptions options;
    options.per_step = 6;
    out.observed = observe_gridworld(out.task.mdp, out.task.trajectories, subject, elements, options, rng).trajectories;
    const std::vector<Trajectory> controlled =
        soft_expert_demonstration(out.task.mdp, out.task.true_weights, 20, 10, rng);
    out.prior.num_symbols = 4;
    out.prior.num_confounders = 3;
    out.prior.subject_alpha = controlled_run_alpha(out.task.mdp, controlled, subject, 6, 1.0, rng);
    out.prior.confounder_alpha = Eigen::MatrixXd::Ones(3, 4);
    out.prior.c = 0.5;
    out.prior.learn_eta = false;  // eta as stated here; with_learned_eta() below learns it
    return out;
  }();
  return t;
}

LearnResult learn(const Task& t, std::shared_ptr<BlockExecutor> executor) {
  ObservationEStepOptions options;
  options.executor = std::move(executor);
  const ObservationEStep estep(t.task.mdp, t.observed, t.prior, options);
  LearnOptions learn;
  learn.seed = 3;
  learn.threads = 1;
  learn.max_em_iterations = 12;  // identity, not convergence, is the point: keep the sanitizer build quick
  return learn_reward(t.task.mdp, estep, learn);
}

LearnResult learn(std::shared_ptr<BlockExecutor> executor) { return learn(task(), std::move(executor)); }

// The task with learned eta (the service set's default): with contexts given (five, made
// up from the observations) or, without, each distinct eta its own context.
Task with_learned_eta(bool given_contexts) {
  Task t = task();
  t.prior.learn_eta = true;
  if (given_contexts) {
    for (auto& o : t.observed) {
      o.contexts.resize(static_cast<size_t>(o.num_observations()));
      for (int n = 0; n < o.num_observations(); ++n)
        o.contexts[static_cast<size_t>(n)] = (7 * n + o.symbols[static_cast<size_t>(n)]) % 5;
    }
  }
  return t;
}

const LearnResult& local() {
  static const LearnResult r = learn(nullptr);
  return r;
}

void expect_identical(const LearnResult& a, const LearnResult& b) {
  ASSERT_EQ(a.theta.size(), b.theta.size());
  for (Eigen::Index k = 0; k < a.theta.size(); ++k) EXPECT_EQ(a.theta[k], b.theta[k]) << "theta[" << k << "]";
  EXPECT_EQ(a.log_likelihood, b.log_likelihood);
}

TaskWorker::TaskWorker(std::shared_ptr<MemoryHub> hub, const std::string& id, std::int64_t die_after, bool lying)
    : testing::WorkerThread(std::move(hub), id, die_after, lying) {}

struct Optimiser {
  explicit Optimiser(std::shared_ptr<MemoryHub> hub, BusExecutorOptions options = {}, const Task& t = task())
      : bus(std::move(hub)),
        counters(quiet("optimiser")),
        executor(std::make_shared<BusBlockExecutor>(bus, t.task.mdp, "gridworld", counters, options)) {}
  MemoryBus bus;
  Counters counters;
  std::shared_ptr<BusBlockExecutor> executor;
};

// An answer carries end counts exactly when its block's trajectories have end reports, in
// O_end's shape: a worker that leaves them out (or adds them) is refused, naming the field.
TEST(EStepService, EndCountsComeFromTheBlocksWithEndReports) {
  ResultShape shape;
  shape.blocks = 2;
  shape.pairs = 3;
  shape.symbols = 2;
  shape.end_rows = 4;
  shape.end_symbols = 2;
  shape.end_reported = {1, 0};
  hbirl::estep_result_t m{};
  m.num_pairs = 3;
  m.num_symbols = 2;
  m.block = 0;
  m.num_end_rows = 4;
  m.num_end_symbols = 2;
  EXPECT_NO_THROW(check_shape(m, shape));
  m.num_end_rows = 0;
  hbirl::testing::expect_refused([&] { check_shape(m, shape); }, "estep_result.num_end_rows");
  m.block = 1;
  EXPECT_NO_THROW(check_shape(m, shape));
  m.num_end_rows = 4;
  hbirl::testing::expect_refused([&] { check_shape(m, shape); }, "estep_result.num_end_rows");
}

TEST(EStepService, TrajectoriesRoundTrip) {
  const auto& observed = task().observed;
  std::vector<ObservedTrajectory> back;
  for (size_t i = 0; i < observed.size(); ++i) {
    back.push_back(
        from_message(to_message(observed[i], static_cast<int>(i), static_cast<int>(observed.size()), 1, "w")));
  }
  EXPECT_EQ(dataset_digest(back), dataset_digest(observed));
  hbirl::trajectory_t bad = to_message(observed[0], 0, 1, 1, "w");
  bad.step_begin[1] = bad.n + 5;
  EXPECT_THROW(from_message(bad), InputError);
  bad = to_message(observed[0], 0, 1, 1, "w");
  bad.eta[0][0] = std::nan("");
  EXPECT_THROW(from_message(bad), InputError);
  // Contexts go with the data (and into its digest).
  const std::vector<ObservedTrajectory> with_contexts = with_learned_eta(true).observed;
  back.clear();
  for (size_t i = 0; i < with_contexts.size(); ++i) {
    back.push_back(from_message(
        to_message(with_contexts[i], static_cast<int>(i), static_cast<int>(with_contexts.size()), 1, "w")));
  }
  EXPECT_EQ(dataset_digest(back), dataset_digest(with_contexts));
  EXPECT_NE(dataset_digest(back), dataset_digest(observed));
  // What was seen of the end goes with the data too (and into its digest).
  ObservedTrajectory ended = observed[0];
  ended.ends_in_terminal = true;
  ended.end_state = 7;
  ended.end_symbols = {1, 0, 1};
  const ObservedTrajectory ended_back = from_message(to_message(ended, 0, 1, 1, "w"));
  EXPECT_EQ(ended_back.end_state, 7);
  EXPECT_EQ(ended_back.end_symbols, ended.end_symbols);
  EXPECT_EQ(dataset_digest(std::span(&ended_back, 1)), dataset_digest(std::span(&ended, 1)));
  hbirl::trajectory_t unknown = to_message(observed[0], 0, 1, 1, "w");
  EXPECT_FALSE(unknown.end_state_known);
  EXPECT_EQ(from_message(unknown).end_state, -1);
  const auto refused = [](const hbirl::trajectory_t& m, const std::string& field) {
    hbirl::testing::expect_refused([&] { from_message(m); }, field);
  };
  bad = to_message(with_contexts[0], 0, 1, 1, "w");
  bad.context[1] = kMaxContexts;
  refused(bad, "trajectory.context");
  bad = to_message(with_contexts[0], 0, 1, 1, "w");
  bad.context.pop_back();
  bad.num_context -= 1;
  refused(bad, "trajectory.num_context");
}

// The learned theta is bit-identical to learning without the bus, with 1, 2 and 4
// workers: every block is computed by the same code and summed in block order.
// The MDP goes over the bus in chunks and comes back identical; a chunk that does not
// fit, a digest that does not match or dynamics that are not an MDP are refused naming
// the field, and the assembler takes the next MDP afterwards.
TEST(EStepService, MdpRoundTripsInChunksAndBadOnesAreRefused) {
  const Mdp& mdp = task().task.mdp;
  const std::vector<hbirl::mdp_t> chunks = to_messages(mdp, "gridworld", 100);
  ASSERT_EQ(chunks.size(), static_cast<size_t>((mdp.transitions.nonZeros() + 99) / 100));
  MdpAssembler assembler;
  std::optional<Mdp> got;
  for (auto it = chunks.rbegin(); it != chunks.rend(); ++it) {  // any order, repeats ignored
    ASSERT_FALSE(got.has_value());
    got = assembler.add(*it);
    if (!got && it != chunks.rbegin()) {
      EXPECT_FALSE(assembler.add(*it).has_value());
    }
  }
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(dynamics_digest(*got), dynamics_digest(mdp));
  EXPECT_TRUE(got->transitions.isApprox(mdp.transitions, 0.0));
  EXPECT_EQ(got->start, mdp.start);
  const auto refused = [](std::vector<hbirl::mdp_t> messages, const std::string& field) {
    MdpAssembler a;
    hbirl::testing::expect_refused(
        [&] {
          for (const auto& m : messages) a.add(m);
        },
        field);
  };
  auto bad = chunks;
  bad[0].num_states = -3;
  refused(bad, "mdp.num_states");
  bad = chunks;
  bad[1].chunk = 99;
  refused(bad, "mdp.chunk");
  bad = chunks;
  bad[1].next_state[0] = 25;
  refused(bad, "mdp.transition[0]");
  bad = chunks;
  bad[0].probability[0] = std::nan("");
  refused(bad, "mdp.transition[0]");
  bad = chunks;
  bad[0].probability[0] *= 0.5;  // its row no longer sums to 1
  refused(bad, "mdp.transitions");
  bad = chunks;
  for (auto& m : bad) m.mdp_digest ^= 1;
  refused(bad, "mdp.mdp_digest");
  bad = chunks;
  bad[0].num_start = 2;
  refused(bad, "mdp.num_start");
  // After a refusal, a good MDP is taken.
  MdpAssembler again;
  hbirl::mdp_t broken = chunks[0];
  broken.next_state[0] = -1;
  EXPECT_THROW(again.add(broken), InputError);
  std::optional<Mdp> second;
  for (const auto& m : chunks) second = again.add(m);
  EXPECT_TRUE(second.has_value());
}

// The watched trajectory's posterior (what the optimiser shows of its E-step) comes back
// from the worker whose block holds it, bit for bit what the E-step computes in one process.
TEST(EStepService, WatchedPosteriorComesBackFromTheWorkers) {
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker a(hub, "sampler-a"), b(hub, "sampler-b");
  Optimiser opt(hub);
  ASSERT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
  const Task& t = task();
  const SoftSolution policy = soft_value_iteration(t.task.mdp, t.task.mdp.reward(t.task.true_weights));
  for (int watch : {39, 3}) {  // in the last block, in the first
    ObservationEStepOptions here, there;
    here.watch = there.watch = watch;
    there.executor = opt.executor;
    EStepState s1, s2;
    const EStepResult local_result = ObservationEStep(t.task.mdp, t.observed, t.prior, here).expect(policy, s1);
    const EStepResult remote = ObservationEStep(t.task.mdp, t.observed, t.prior, there).expect(policy, s2);
    ASSERT_EQ(remote.watched.rows(), t.observed[static_cast<size_t>(watch)].length()) << watch;
    EXPECT_EQ(remote.watched, local_result.watched) << watch;
    EXPECT_EQ(remote.watched_log_likelihood, local_result.watched_log_likelihood);
  }
  EXPECT_EQ(opt.executor->stats().local_blocks, 0);
}

TEST(EStepService, SameThetaWithOneTwoOrFourWorkers) {
  for (int n : {1, 2, 4}) {
    auto hub = std::make_shared<MemoryHub>();
    std::vector<std::unique_ptr<TaskWorker>> workers;
    for (int w = 0; w < n; ++w) workers.push_back(std::make_unique<TaskWorker>(hub, "sampler-" + std::to_string(w)));
    Optimiser opt(hub);
    ASSERT_EQ(opt.executor->wait_for_workers(n, 10000), n);
    expect_identical(learn(opt.executor), local());
    const auto stats = opt.executor->stats();
    EXPECT_GT(stats.remote_blocks, 0) << n << " workers";
    EXPECT_EQ(stats.local_blocks, 0) << n << " workers";
    // 40 trajectories are 3 blocks: each goes to a different worker (and a worker that has
    // not answered yet is given one block of a later pass: all four get work).
    int busy = 0;
    for (const auto& w : workers) busy += w->worker().blocks_computed() > 0;
    EXPECT_EQ(busy, n) << n << " workers";
  }
}

// Learned eta over the bus: each pass's request carries every context's eta, the workers
// give each context's expected source counts with their blocks, and theta, the
// likelihood and the learned eta are bit-identical to learning in one process -- with the
// contexts given with the data (sent to the workers with it) and with each distinct eta
// its own context (the workers number them as the optimiser does).
TEST(EStepService, LearnedEtaOverTheBusIsBitIdentical) {
  for (const bool given : {true, false}) {
    const Task t = with_learned_eta(given);
    const LearnResult here = learn(t, nullptr);
    auto hub = std::make_shared<MemoryHub>();
    TaskWorker a(hub, "sampler-a"), b(hub, "sampler-b");
    Optimiser opt(hub, {}, t);
    ASSERT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
    const LearnResult there = learn(t, opt.executor);
    expect_identical(there, here);
    const RestartResult& h = here.restarts[static_cast<size_t>(here.selected_restart)];
    const RestartResult& r = there.restarts[static_cast<size_t>(there.selected_restart)];
    ASSERT_TRUE(h.alpha && r.alpha);
    ASSERT_GT(h.alpha->eta_alpha.rows(), 0) << "eta was not learned";
    if (given) {
      EXPECT_EQ(h.alpha->eta_alpha.rows(), 5);
    }
    EXPECT_EQ(r.alpha->eta_alpha, h.alpha->eta_alpha) << (given ? "given contexts" : "each distinct eta");
    const auto stats = opt.executor->stats();
    EXPECT_GT(stats.remote_blocks, 0);
    EXPECT_EQ(stats.local_blocks, 0);
    EXPECT_EQ(stats.liars, 0);
  }
}

// Learned eta with more contexts than a request carries (BusExecutorOptions::max_contexts;
// a sensor whose every eta differs has one per observation) is computed by the optimiser
// itself: the same bits, no work for the workers.
TEST(EStepService, TooManyContextsForTheBusAreComputedHere) {
  const Task t = with_learned_eta(true);  // five contexts
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker worker(hub, "sampler-a");
  BusExecutorOptions options;
  options.max_contexts = 4;
  Optimiser opt(hub, options, t);
  ASSERT_EQ(opt.executor->wait_for_workers(1, 10000), 1);
  expect_identical(learn(t, opt.executor), learn(t, nullptr));
  const auto stats = opt.executor->stats();
  EXPECT_EQ(stats.remote_blocks, 0);
  EXPECT_GT(stats.local_blocks, 0);
  EXPECT_EQ(worker.worker().blocks_computed(), 0);
}

// Two different answers to one block under one worker's name -- here the worker's own
// answer to block 0 followed at once by a forged copy, added by a relay between the
// worker and the optimiser, so the order is certain -- make the optimiser compute every
// block of that pass answered under the name itself: theta bit-identical, the conflict
// counted each pass, and the worker keeps its work (a forger must not be able to bench it).
TEST(EStepService, TwoDifferentAnswersUnderOneNameAreNotUsed) {
  auto hub = std::make_shared<MemoryHub>();     // the optimiser's side
  auto behind = std::make_shared<MemoryHub>();  // the worker's side of the relay
  TaskWorker worker(behind, "sampler-a");
  MemoryBus front(hub), back(behind);
  std::atomic<int> forged{0};
  const auto forward_to = [](MemoryBus& to) {
    return [&to](const Message& m) { to.publish(m.channel, m.data, m.size); };
  };
  for (const std::string& channel :
       {channels::kEStepRequest.name, channels::kMdp.name, channels::trajectory_channel("sampler-a").name}) {
    front.subscribe(channel, forward_to(back), 100000);
  }
  back.subscribe(channels::kStatus.name, forward_to(front), 1000);
  back.subscribe(
      channels::kEStepResult.name,
      [&](const Message& m) {
        front.publish(m.channel, m.data, m.size);
        hbirl::estep_result_t r;
        if (r.decode(m.data, 0, m.size) < 0 || r.block != 0 || r.counts.empty()) return;
        r.counts[0] += 1.0;
        std::vector<std::uint8_t> bytes(static_cast<size_t>(r.getEncodedSize()));
        r.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
        front.publish(m.channel, bytes.data(), static_cast<int>(bytes.size()));
        ++forged;
      },
      100000);
  std::atomic<bool> stop{false};
  std::thread relay([&] {
    while (!stop) {
      front.handle(1);
      back.handle(1);
    }
  });
  Optimiser opt(hub);
  ASSERT_EQ(opt.executor->wait_for_workers(1, 10000), 1);
  expect_identical(learn(opt.executor), local());
  stop = true;
  relay.join();
  const auto stats = opt.executor->stats();
  EXPECT_GT(forged, 0);
  EXPECT_EQ(stats.conflicts, stats.requests);  // block 0 of every pass
  EXPECT_EQ(stats.remote_blocks, 0);           // no answer under the name was used
  EXPECT_EQ(stats.liars, 0);                   // and it was not benched
  EXPECT_GT(worker.worker().blocks_computed(), 3);
}

// A worker dies mid-run: its blocks time out, go to the worker that answers, and the
// result is still bit-identical.
TEST(EStepService, WorkerKilledMidRunSameTheta) {
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker steady(hub, "sampler-a");
  TaskWorker doomed(hub, "sampler-b", 5);
  BusExecutorOptions options;
  options.timeout_ms = 300;
  options.worker_silence_s = 2.5;  // > the 1 s heartbeat, with room for a loaded machine
  Optimiser opt(hub, options);
  ASSERT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
  expect_identical(learn(opt.executor), local());
  const auto stats = opt.executor->stats();
  EXPECT_GT(stats.retried_blocks, 0);
  EXPECT_GE(doomed.worker().blocks_computed(), 5);
}

// A worker that misses a request (here a relay drops the first one it would get) leaves its
// blocks unanswered, gets no work while it is silent, and once its next heartbeat comes it
// gets work again -- one block, then its share -- instead of being left out for the run.
// Passes that re-ask after 300 ms without progress, not 2 s.
BusExecutorOptions short_timeout() {
  BusExecutorOptions options;
  options.timeout_ms = 300;
  return options;
}

// The task's E-step over an optimiser's workers and the same E-step's pass in one process,
// at the true reward and the prior's mean O.
struct RemoteAndLocal {
  explicit RemoteAndLocal(std::shared_ptr<BlockExecutor> executor, const Task& t = task())
      : there(t.task.mdp, t.observed, t.prior, with_executor(std::move(executor))),
        model(dirichlet_mean(t.prior)),
        policy(soft_value_iteration(t.task.mdp, t.task.mdp.reward(t.task.true_weights))),
        here(ObservationEStep(t.task.mdp, t.observed, t.prior).statistics(policy, model, 5)) {}
  static ObservationEStepOptions with_executor(std::shared_ptr<BlockExecutor> executor) {
    ObservationEStepOptions o;
    o.executor = std::move(executor);
    return o;
  }
  const ObservationEStep there;
  const ObservationModel model;
  const SoftSolution policy;
  const EStepStatistics here;
};

TEST(EStepService, AWorkerThatMissedARequestGetsWorkAgain) {
  auto hub = std::make_shared<MemoryHub>();
  auto behind = std::make_shared<MemoryHub>();
  TaskWorker steady(hub, "sampler-a");
  TaskWorker missing(behind, "sampler-b");
  MemoryBus front(hub), back(behind);
  std::atomic<int> dropped{0};
  const auto forward_to = [](MemoryBus& to) {
    return [&to](const Message& m) { to.publish(m.channel, m.data, m.size); };
  };
  front.subscribe(
      channels::kEStepRequest.name,
      [&](const Message& m) {
        if (dropped++ == 0) return;  // the first request never reaches it
        back.publish(m.channel, m.data, m.size);
      },
      100000);
  front.subscribe(channels::kMdp.name, forward_to(back), 100000);
  front.subscribe(channels::trajectory_channel("sampler-b").name, forward_to(back), 100000);
  back.subscribe(channels::kStatus.name, forward_to(front), 1000);
  back.subscribe(channels::kEStepResult.name, forward_to(front), 100000);
  std::atomic<bool> stop{false};
  std::thread relay([&] {
    while (!stop) {
      front.handle(1);
      back.handle(1);
    }
  });
  Optimiser opt(hub, short_timeout());
  ASSERT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
  const RemoteAndLocal r(opt.executor);
  const auto& [there, model, policy, here] = r;
  for (int pass = 0; pass < 8 && missing.worker().blocks_computed() == 0; ++pass) {
    EXPECT_EQ(there.statistics(policy, model, 5).counts, here.counts) << pass;
    std::this_thread::sleep_for(std::chrono::milliseconds(300));  // its heartbeat comes
  }
  stop = true;
  relay.join();
  EXPECT_GT(dropped, 1);
  EXPECT_GT(missing.worker().blocks_computed(), 0) << "left out after one missed request";
  EXPECT_GT(opt.executor->stats().retried_blocks, 0);
}

// No worker at all: the optimiser computes every block itself; learning does not stall.
TEST(EStepService, NoWorkersComputesLocally) {
  auto hub = std::make_shared<MemoryHub>();
  BusExecutorOptions options;
  options.timeout_ms = 100;
  Optimiser opt(hub, options);
  EXPECT_EQ(opt.executor->wait_for_workers(1, 100), 0);
  expect_identical(learn(opt.executor), local());
  EXPECT_EQ(opt.executor->stats().remote_blocks, 0);
  EXPECT_GT(opt.executor->stats().local_blocks, 0);
}

// Duplicated and stale answers, garbage and wrong-type messages on every channel of the
// protocol: counted, ignored, and theta is still bit-identical.
TEST(EStepService, DuplicatesStaleAnswersAndGarbageAreIgnored) {
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker worker(hub, "sampler-a");
  // A meddler: repeats every answer twice (once as stale) and sprays garbage.
  MemoryBus meddler(hub);
  Counters meddler_counters = quiet("meddler");
  std::atomic<bool> stop{false};
  subscribe(
      meddler, channels::kEStepResult, meddler_counters,
      [&](const hbirl::estep_result_t& m, const Message&) {
        if (m.worker == "meddler") return;
        hbirl::estep_result_t copy = m;
        copy.worker = "meddler";
        publish(meddler, channels::kEStepResult, copy, meddler_counters);
        copy.request_id -= 1;
        publish(meddler, channels::kEStepResult, copy, meddler_counters);
        const char garbage[] = "garbage";
        for (const std::string& ch : {channels::kEStepResult.name, channels::kEStepRequest.name,
                                      channels::trajectory_channel("sampler-a").name, channels::kStatus.name}) {
          meddler.publish(ch, garbage, sizeof garbage);
        }
      },
      1000);
  std::thread meddling([&] {
    while (!stop) meddler.handle(20);
  });
  Optimiser opt(hub);
  ASSERT_EQ(opt.executor->wait_for_workers(1, 10000), 1);
  expect_identical(learn(opt.executor), local());
  stop = true;
  meddling.join();
  worker.stop();
  const auto stats = opt.executor->stats();
  EXPECT_GT(stats.duplicates, 0);
  EXPECT_GT(stats.stale, 0);
  EXPECT_GT(opt.counters.bad_messages, 0);
  EXPECT_GT(worker.counters().bad_messages, 0);
}

// A block's declared data set size takes no memory until its trajectories arrive (a
// 61-byte TRAJECTORY claiming 10 million used to make a worker allocate 1.1 GB), and blocks
// beyond the worker's --max-dataset-mb are refused and dropped.
// A worker of every run of a shared key that starts after the optimiser sent its MDP hears
// no MDP and no request (none is sent to a worker nobody has heard): it follows the
// optimiser whose heartbeat it hears, so its own heartbeat reaches that optimiser (which
// then sends it the MDP). Before, it signed for no run and was never used in the run.
TEST(SamplerWorker, AWorkerOfEveryRunFollowsTheOptimiserItHears) {
  auto hub = std::make_shared<MemoryHub>();
  const RunKey shared = RunKey::generate();
  const RunKey run_a = shared.for_new_run();
  Counters cw = quiet("sampler-late"), co = quiet("optimiser");
  KeyedBus worker_bus(std::make_unique<MemoryBus>(hub), shared, cw, KeyUse::kWorker);
  KeyedBus optimiser_bus(std::make_unique<MemoryBus>(hub), run_a, co);
  std::vector<std::string> heard;
  subscribe(optimiser_bus, channels::kStatus, co,
            [&](const hbirl::service_status_t& m, const Message&) { heard.push_back(m.id); });
  SamplerWorker worker(worker_bus, "sampler-late", cw);
  worker.publish_status();
  optimiser_bus.handle(0);
  EXPECT_TRUE(heard.empty()) << "a worker of no run yet sent a heartbeat";
  hbirl::service_status_t beat{};
  beat.service = "optimiser";
  beat.id = "optimiser-1";
  beat.state = "collecting";
  publish(optimiser_bus, channels::kStatus, beat, co);
  worker.handle(0);
  worker.publish_status();
  optimiser_bus.handle(0);
  EXPECT_EQ(heard, (std::vector<std::string>{"optimiser-1", "sampler-late"}));
  EXPECT_EQ(co.other_run, 0);
}

TEST(SamplerWorker, DeclaredDataSetSizesTakeNoMemory) {
  const auto max_rss_kb = [] {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss;
  };
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub), sender(hub);
  Counters counters = quiet("sampler"), out = quiet("sender");
  SamplerWorker worker(bus, "sampler-a", counters, std::int64_t{1} << 20);
  const Channel<hbirl::trajectory_t> channel = channels::trajectory_channel("sampler-a");
  hbirl::trajectory_t claim = to_message(task().observed[0], 5, 10'000'000, 42, "sampler-a");
  const long before = max_rss_kb();
  publish(sender, channel, claim, out);
  bus.handle(0);
  EXPECT_LT(max_rss_kb() - before, 50 * 1024) << "kB more at the peak";
  EXPECT_EQ(counters.bad_messages, 0);  // a fine message: its block is just not complete
  // The first trajectory of 1000 made-up blocks, each ~2.5 KB held: past 1 MB after ~430.
  for (int i = 0; i < 1000; ++i) {
    publish(sender, channel,
            to_message(task().observed[0], i * ObservationEStep::kBlockSize, 1000 * ObservationEStep::kBlockSize,
                       static_cast<std::uint64_t>(1000 + i), "sampler-a"),
            out);
  }
  bus.handle(0);
  EXPECT_GT(counters.bad_messages, 0);
  EXPECT_NE(counters.last_problem.find("--max-dataset-mb"), std::string::npos) << counters.last_problem;
  EXPECT_EQ(worker.trajectories_held(), 0);  // nothing complete was taken in
  // A whole block whose trajectories do not have the digest it is sent under is refused.
  Counters fresh = quiet("sampler-b");
  SamplerWorker b(bus, "sampler-b", fresh);
  const std::span<const ObservedTrajectory> first = block_of(task().observed, 0);
  for (int i = 0; i < ObservationEStep::kBlockSize; ++i) {
    publish(sender, channels::trajectory_channel("sampler-b"),
            to_message(first[static_cast<size_t>(i)], i, 40, dataset_digest(first) ^ 1, "sampler-b"), out);
  }
  bus.handle(0);
  EXPECT_NE(fresh.last_problem.find("trajectory.block_digest"), std::string::npos) << fresh.last_problem;
  EXPECT_EQ(b.trajectories_held(), 0);
  // Sent under its own digest, it is held.
  for (int i = 0; i < ObservationEStep::kBlockSize; ++i) {
    publish(sender, channels::trajectory_channel("sampler-b"),
            to_message(first[static_cast<size_t>(i)], i, 40, dataset_digest(first), "sampler-b"), out);
  }
  bus.handle(0);
  EXPECT_EQ(b.trajectories_held(), ObservationEStep::kBlockSize);
}

// A second attempt of a request that names other blocks than its first (a forger re-using
// a live request's id) is refused naming the field -- it used to make the worker read past
// the new request's arrays for the blocks the first one left pending.
TEST(SamplerWorker, AnotherAttemptWithOtherBlocksIsRefused) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub), sender(hub);
  Counters counters = quiet("sampler"), out = quiet("sender");
  SamplerWorker worker(bus, "sampler-a", counters);
  for (const auto& m : to_messages(task().task.mdp, "gridworld")) publish(sender, channels::kMdp, m, out);
  bus.handle(0);
  ASSERT_NE(worker.mdp_digest(), 0u);
  const int P = task().task.mdp.num_pairs();
  hbirl::estep_request_t r{};
  r.request_id = 7;
  r.mdp_digest = static_cast<std::int64_t>(worker.mdp_digest());
  r.num_trajectories = 40, r.block_size = ObservationEStep::kBlockSize, r.num_blocks = 3;
  r.assigned_worker = {"sampler-a", "sampler-a", "sampler-a"};
  r.block_digest = {11, 12, 13};  // blocks it does not hold: pending
  r.engine = "exact", r.watch = -1, r.max_kinds = 1024;
  r.num_pairs = P, r.log_policy.assign(static_cast<size_t>(P), -1.0), r.policy.assign(static_cast<size_t>(P), 0.25);
  r.num_symbols = 4, r.num_confounders = 3;
  r.subject_o.assign(static_cast<size_t>(P), std::vector<double>(4, 0.25));
  r.confounder_o.assign(3, std::vector<double>(4, 0.25));
  publish(sender, channels::kEStepRequest, r, out);
  bus.handle(0);
  EXPECT_EQ(counters.bad_messages, 0) << counters.last_problem;
  r.attempt = 1, r.num_trajectories = 16, r.num_blocks = 1;
  r.assigned_worker = {"sampler-a"};
  r.block_digest = {11};
  publish(sender, channels::kEStepRequest, r, out);
  bus.handle(0);
  EXPECT_EQ(counters.bad_messages, 1);
  EXPECT_NE(counters.last_problem.find("estep_request.block_digest"), std::string::npos) << counters.last_problem;
  worker.handle(300);  // past the quiet time: what is pending is served, within its own request's arrays
  EXPECT_EQ(worker.blocks_computed(), 0);
}

// The E-step a worker computes with holds the worker's blocks (each trajectory held once,
// issue 35): a request that does not fit them -- refused by the worker's check, or by the
// E-step as it is made -- leaves them as they were, and the next request gets the same
// answer, bit for bit, as before.
TEST(SamplerWorker, ARequestThatDoesNotFitLeavesItsBlocksAsTheyWere) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus bus(hub), sender(hub);
  Counters counters = quiet("sampler"), out = quiet("sender");
  SamplerWorker worker(bus, "sampler-a", counters);
  std::vector<hbirl::estep_result_t> answers;
  subscribe(sender, channels::kEStepResult, out,
            [&](const hbirl::estep_result_t& m, const Message&) { answers.push_back(m); });
  for (const auto& m : to_messages(task().task.mdp, "gridworld")) publish(sender, channels::kMdp, m, out);
  bus.handle(0);
  const std::span<const ObservedTrajectory> first = block_of(task().observed, 0);
  const std::vector<ObservedTrajectory> block(first.begin(), first.end());
  for (int i = 0; i < ObservationEStep::kBlockSize; ++i) {
    publish(
        sender, channels::trajectory_channel("sampler-a"),
        to_message(block[static_cast<size_t>(i)], i, ObservationEStep::kBlockSize, dataset_digest(block), "sampler-a"),
        out);
  }
  bus.handle(0);
  ASSERT_EQ(worker.trajectories_held(), ObservationEStep::kBlockSize);
  const int P = task().task.mdp.num_pairs();
  hbirl::estep_request_t r{};
  r.mdp_digest = static_cast<std::int64_t>(worker.mdp_digest());
  r.num_trajectories = ObservationEStep::kBlockSize, r.block_size = ObservationEStep::kBlockSize, r.num_blocks = 1;
  r.assigned_worker = {"sampler-a"};
  r.block_digest = {static_cast<std::int64_t>(dataset_digest(block))};
  r.engine = "exact", r.watch = -1, r.max_kinds = 1024;
  r.num_pairs = P, r.log_policy.assign(static_cast<size_t>(P), std::log(0.25));
  r.policy.assign(static_cast<size_t>(P), 0.25);
  r.num_symbols = 4, r.num_confounders = 3;
  r.subject_o.assign(static_cast<size_t>(P), std::vector<double>{0.4, 0.3, 0.2, 0.1});
  r.confounder_o.assign(3, std::vector<double>(4, 0.25));
  const auto ask = [&](std::int64_t id) {
    r.request_id = id;
    publish(sender, channels::kEStepRequest, r, out);
    bus.handle(0);
    sender.handle(0);
  };
  ask(1);
  ASSERT_EQ(answers.size(), 1u) << counters.last_problem;
  // Refused by the worker's check: fewer symbols than the blocks use.
  r.num_symbols = 2;
  r.subject_o.assign(static_cast<size_t>(P), std::vector<double>{0.5, 0.5});
  r.confounder_o.assign(3, std::vector<double>(2, 0.5));
  ask(2);
  EXPECT_NE(counters.last_problem.find("estep_request.num_symbols"), std::string::npos) << counters.last_problem;
  // Refused by the E-step as it is made: an end sensor's model of one row, not one per state.
  r.num_symbols = 4;
  r.subject_o.assign(static_cast<size_t>(P), std::vector<double>{0.4, 0.3, 0.2, 0.1});
  r.confounder_o.assign(3, std::vector<double>(4, 0.25));
  r.num_end_rows = 1, r.num_end_symbols = 2, r.end_o = {{0.5, 0.5}};
  ask(3);
  EXPECT_NE(counters.last_problem.find("end_alpha"), std::string::npos) << counters.last_problem;
  EXPECT_EQ(worker.trajectories_held(), ObservationEStep::kBlockSize);
  r.num_end_rows = 0, r.num_end_symbols = 0, r.end_o.clear();
  ask(4);
  ASSERT_EQ(answers.size(), 2u) << counters.last_problem;
  EXPECT_EQ(answers[1].counts, answers[0].counts);
  EXPECT_EQ(answers[1].alpha_subject, answers[0].alpha_subject);
  EXPECT_EQ(answers[1].log_likelihood, answers[0].log_likelihood);
  EXPECT_EQ(counters.bad_messages, 2);
}

// A worker that lies about its blocks is caught by the optimiser's spot check in the first
// pass (every block it answers is wrong, and one of them is checked), gets no more work,
// and theta is the one-process run's, bit for bit.
TEST(EStepService, LyingWorkerIsCaughtBySpotCheck) {
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker honest(hub, "sampler-a");
  TaskWorker liar(hub, "sampler-b", -1, true);
  Optimiser opt(hub);
  ASSERT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
  expect_identical(learn(opt.executor), local());
  const auto stats = opt.executor->stats();
  EXPECT_EQ(stats.liars, 1);
  EXPECT_GT(stats.spot_checks, 0);
  EXPECT_GT(opt.counters.bad_messages, 0);
  EXPECT_GT(honest.worker().blocks_computed(), liar.worker().blocks_computed());
}

// A worker that always lies is caught in the very first pass it works in, whichever block
// it is given: the first answer of every worker is checked (a randomly chosen block, as
// before, missed it two times in three). Five fresh runs, each one pass compared bit for
// bit with the pass computed in one process.
TEST(EStepService, AWorkerThatAlwaysLiesIsCaughtInItsFirstPass) {
  const Task& t = task();
  const SoftSolution policy = soft_value_iteration(t.task.mdp, t.task.mdp.reward(t.task.true_weights));
  const ObservationModel model = dirichlet_mean(t.prior);
  const ObservationEStep here(t.task.mdp, t.observed, t.prior);
  std::vector<int> all(static_cast<size_t>(here.num_blocks()));
  std::iota(all.begin(), all.end(), 0);
  const std::vector<EStepStatistics> truth = here.block_statistics(policy, model, 7, all, 1);
  for (int run = 0; run < 5; ++run) {
    auto hub = std::make_shared<MemoryHub>();
    TaskWorker honest(hub, "sampler-a");
    TaskWorker liar(hub, "sampler-b", -1, true);
    Optimiser opt(hub);
    ASSERT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
    ObservationEStepOptions options;
    options.executor = opt.executor;
    const ObservationEStep over_bus(t.task.mdp, t.observed, t.prior, options);
    const std::vector<EStepStatistics> got = opt.executor->run(over_bus, policy, model, 7);
    ASSERT_EQ(got.size(), truth.size());
    for (size_t b = 0; b < got.size(); ++b) {
      EXPECT_EQ(got[b].counts, truth[b].counts) << "run " << run << ", block " << b;
      EXPECT_EQ(got[b].log_likelihood, truth[b].log_likelihood) << "run " << run << ", block " << b;
    }
    EXPECT_EQ(opt.executor->stats().liars, 1) << "run " << run;  // it answered, and was caught
  }
}

// Forged answers -- the request's id and digests echoed, statistics made up, sent before
// the real worker's -- are refused when they name a worker the block was not given to,
// and caught by the spot check when they name the one it was: theta stays bit-identical.
TEST(EStepService, ForgedAnswersDoNotChangeTheta) {
  for (const bool name_the_assigned_worker : {false, true}) {
    auto hub = std::make_shared<MemoryHub>();
    TaskWorker worker(hub, "sampler-a");
    MemoryBus forger(hub);
    Counters forger_counters = quiet("forger");
    std::atomic<bool> stop{false};
    subscribe(
        forger, channels::kEStepRequest, forger_counters,
        [&](const hbirl::estep_request_t& m, const Message&) {
          for (int b = 0; b < m.num_blocks; ++b) {
            const std::string& to = m.assigned_worker[static_cast<size_t>(b)];
            if (to.empty()) continue;
            hbirl::estep_result_t r{};
            r.request_id = m.request_id;
            r.worker = name_the_assigned_worker ? to : "forger";
            r.block_digest = m.block_digest[static_cast<size_t>(b)];
            r.block = b;
            r.num_pairs = m.num_pairs;
            r.counts.assign(static_cast<size_t>(m.num_pairs), 1.0);
            r.num_symbols = m.num_symbols;
            r.num_confounders = m.num_confounders;
            r.alpha_subject.assign(static_cast<size_t>(m.num_pairs),
                                   std::vector<double>(static_cast<size_t>(m.num_symbols), 1.0));
            r.alpha_confounder.assign(static_cast<size_t>(m.num_confounders),
                                      std::vector<double>(static_cast<size_t>(m.num_symbols), 1.0));
            r.log_likelihood = -1.0;
            publish(forger, channels::kEStepResult, r, forger_counters);
          }
        },
        1000);
    std::thread forging([&] {
      while (!stop) forger.handle(5);
    });
    Optimiser opt(hub);
    ASSERT_EQ(opt.executor->wait_for_workers(1, 10000), 1);
    expect_identical(learn(opt.executor), local());
    stop = true;
    forging.join();
    worker.stop();
    const auto stats = opt.executor->stats();
    if (name_the_assigned_worker) {
      EXPECT_GE(stats.liars, 1);
    } else {
      EXPECT_GT(stats.unassigned, 0);
      EXPECT_EQ(stats.liars, 0);
    }
  }
}

// 300 made-up sampler heartbeats claiming the optimiser's data set and MDP (they used to
// slow a 5 s run to 184 s: every pass gave blocks to workers that never answer). With a
// run key they are dropped unread: no block is re-asked or computed here, theta is the
// one-process run's. Without one, a worker that never answered gets one block per pass:
// the pass still completes with the same theta.
TEST(EStepService, FakeWorkerHeartbeatsCostNothingWithAKey) {
  for (const bool keyed : {true, false}) {
    auto hub = std::make_shared<MemoryHub>();
    const RunKey key = RunKey::generate();
    const auto endpoint = [&](Counters& c) -> std::unique_ptr<Bus> {
      if (!keyed) return std::make_unique<MemoryBus>(hub);
      return std::make_unique<KeyedBus>(std::make_unique<MemoryBus>(hub), key, c);
    };
    Counters wc = quiet("sampler-a"), oc = quiet("optimiser"), fc = quiet("forger");
    std::unique_ptr<Bus> worker_bus = endpoint(wc);
    SamplerWorker worker(*worker_bus, "sampler-a", wc);
    std::atomic<bool> stop{false};
    std::thread working([&] {
      while (!stop) worker.handle(5);
    });
    std::unique_ptr<Bus> opt_bus = endpoint(oc);
    BusExecutorOptions options;
    options.timeout_ms = 300;
    auto executor = std::make_shared<BusBlockExecutor>(*opt_bus, task().task.mdp, "gridworld", oc, options);
    ASSERT_EQ(executor->wait_for_workers(1, 10000), 1);
    MemoryBus forger(hub);
    for (int k = 0; k < 300; ++k) {
      hbirl::service_status_t s{};
      s.service = "sampler";
      s.id = "sampler-fake-" + std::to_string(k);
      s.seq = 1;
      s.state = "running";
      s.mdp_digest = static_cast<std::int64_t>(worker.mdp_digest());
      s.numerics = static_cast<std::int64_t>(numerics_fingerprint());
      publish(forger, channels::kStatus, s, fc);
    }
    expect_identical(learn(executor), local());
    stop = true;
    working.join();
    const auto stats = executor->stats();
    if (keyed) {
      EXPECT_EQ(stats.retried_blocks, 0);
      EXPECT_EQ(stats.local_blocks, 0);
      EXPECT_GE(oc.bad_messages, 300);
    } else {
      EXPECT_GT(stats.remote_blocks, 0);  // the real worker still did the work
    }
  }
}

// Without a key, 300 made-up workers whose heartbeats copy a real worker's -- its MDP, its
// numerics, the blocks it holds -- ten times a second each: each name gets one trial block,
// and once kMaxTrialPasses passes have waited on trials none does; theta is the one-process
// run's. (Before the budget, a name heard from again after leaving its block unanswered
// got another block: every pass waited a timeout, for as long as the forger kept at it.)
TEST(EStepService, FakeWorkersWithoutAKeyCostABoundedNumberOfPasses) {
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker worker(hub, "sampler-a");
  BusExecutorOptions options;
  options.timeout_ms = 200;
  Optimiser opt(hub, options);
  ASSERT_EQ(opt.executor->wait_for_workers(1, 10000), 1);
  std::atomic<bool> stop{false};
  std::atomic<int> rounds{0};  // of ghosts published
  std::thread forging([&] {
    MemoryBus forger(hub);
    Counters fc = quiet("forger");
    hbirl::service_status_t real{};
    forger.subscribe(channels::kStatus.name, [&](const Message& m) {
      hbirl::service_status_t s{};
      if (!decode(m, s) && s.id == "sampler-a") real = s;
    });
    for (std::int64_t seq = 1; !stop; ++seq) {
      forger.handle(100);
      for (int k = 0; k < 300 && real.num_held_blocks > 0; ++k) {
        hbirl::service_status_t ghost = real;
        ghost.id = "ghost-" + std::to_string(k);
        ghost.seq = seq;
        publish(forger, channels::kStatus, ghost, fc);
      }
      if (real.num_held_blocks > 0) ++rounds;
    }
  });
  // A first run gives the worker its blocks (the ghosts copy what it holds); the ghosts are
  // heard before the run that counts, however slowly a loaded machine schedules them.
  learn(opt.executor);
  for (int waited = 0; rounds < 2 && waited < 1000; ++waited)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  const LearnResult result = learn(opt.executor);
  stop = true;
  forging.join();
  expect_identical(result, local());
  const auto stats = opt.executor->stats();
  EXPECT_GT(stats.trial_passes, 0) << "the ghosts were never given work: the test tests nothing";
  EXPECT_LE(stats.trial_passes, BusBlockExecutor::kMaxTrialPasses);
  EXPECT_GT(stats.remote_blocks, 0);
}

// A worker whose build computes other bits (another numerics fingerprint) is heard from,
// counted, and -- with same_numerics_only -- given no work: theta stays bit-identical to
// the one-process run. (It never answers: had it been given blocks, they would have been
// re-asked.)
TEST(EStepService, WorkersWithOtherNumericsCanBeLeftOut) {
  EXPECT_EQ(numerics_fingerprint(), numerics_fingerprint());
  EXPECT_NE(numerics_fingerprint(), 0u);
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker worker(hub, "sampler-a");
  BusExecutorOptions options;
  options.same_numerics_only = true;
  Optimiser opt(hub, options);
  MemoryBus other(hub);
  Counters other_counters = quiet("other");
  std::atomic<bool> stop{false};
  std::thread beating([&] {
    for (std::int64_t seq = 1; !stop; ++seq) {
      hbirl::service_status_t s{};
      s.service = "sampler";
      s.id = "sampler-other-build";
      s.seq = seq;
      s.state = "running";
      s.mdp_digest =
          static_cast<std::int64_t>(worker.worker().mdp_digest());  // it could take work but for its numerics
      s.numerics = static_cast<std::int64_t>(numerics_fingerprint() ^ 1);
      publish(other, channels::kStatus, s, other_counters);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  ASSERT_EQ(opt.executor->wait_for_workers(1, 10000), 1);
  // One E-step pass (every block) through the executor, against the same pass here.
  const Task& t = task();
  ObservationEStepOptions remote;
  remote.executor = opt.executor;
  const SoftSolution policy = soft_value_iteration(t.task.mdp, t.task.mdp.reward(Eigen::Vector4d(0.4, -0.1, 0.2, 0.9)));
  const ObservationModel model = dirichlet_mean(t.prior);
  const EStepStatistics there = ObservationEStep(t.task.mdp, t.observed, t.prior, remote).statistics(policy, model, 5);
  const EStepStatistics here = ObservationEStep(t.task.mdp, t.observed, t.prior).statistics(policy, model, 5);
  EXPECT_EQ(there.log_likelihood, here.log_likelihood);
  EXPECT_EQ(there.counts, here.counts);
  EXPECT_EQ(there.alpha_dot.subject, here.alpha_dot.subject);
  stop = true;
  beating.join();
  const auto stats = opt.executor->stats();
  EXPECT_EQ(stats.other_numerics, 1);
  EXPECT_EQ(stats.retried_blocks, 0);
  EXPECT_EQ(stats.local_blocks, 0);
  EXPECT_GT(stats.remote_blocks, 0);
}

// A worker that starts after learning has begun is given work -- one block while it is
// unproven, then its even share -- and is sent just those blocks, which the worker that
// had them drops: together they hold the data set once, and theta is the one-process run's.
TEST(EStepService, LateWorkerGetsItsShare) {
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker early(hub, "sampler-a");
  Optimiser opt(hub);
  ASSERT_EQ(opt.executor->wait_for_workers(1, 10000), 1);
  const Task& t = task();
  const SoftSolution policy = soft_value_iteration(t.task.mdp, t.task.mdp.reward(t.task.true_weights));
  ObservationEStepOptions remote;
  remote.executor = opt.executor;
  const ObservationEStep there(t.task.mdp, t.observed, t.prior, remote);
  const ObservationModel model = dirichlet_mean(t.prior);
  const EStepStatistics here = ObservationEStep(t.task.mdp, t.observed, t.prior).statistics(policy, model, 5);
  EXPECT_EQ(there.statistics(policy, model, 5).counts, here.counts);
  EXPECT_EQ(early.worker().trajectories_held(), 40);
  TaskWorker late(hub, "sampler-b");
  EXPECT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
  for (int pass = 0; pass < 3; ++pass) {
    const EStepStatistics s = there.statistics(policy, model, 5);
    EXPECT_EQ(s.counts, here.counts) << pass;
    EXPECT_EQ(s.log_likelihood, here.log_likelihood) << pass;
  }
  EXPECT_GT(late.worker().blocks_computed(), 0);
  EXPECT_GT(late.worker().trajectories_held(), 0);
  EXPECT_LT(early.worker().trajectories_held(), 40);
  EXPECT_EQ(early.worker().trajectories_held() + late.worker().trajectories_held(), 40);
  EXPECT_EQ(opt.executor->stats().local_blocks, 0);
}

// A worker that cannot hold the blocks it is sent (here: its --max-dataset-mb is one byte)
// stops being given them: every pass is still the one-process pass bit for bit, the
// blocks end up with the worker that can hold them, and after the first passes no block is
// re-asked.
TEST(EStepService, BlocksAWorkerCannotHoldGoToAnother) {
  auto hub = std::make_shared<MemoryHub>();
  TaskWorker able(hub, "sampler-a");
  testing::WorkerThread small(hub, "sampler-b", -1, false, 1);
  Optimiser opt(hub, short_timeout());
  ASSERT_EQ(opt.executor->wait_for_workers(2, 10000), 2);
  const RemoteAndLocal r(opt.executor);
  const auto& [there, model, policy, here] = r;
  // Each heartbeat (one a second) made the silent worker eligible for one block again, so
  // without the rule no two seconds of passes go by without a block re-asked; with it,
  // once its blocks have failed twice, none is.
  int clean = 0;
  for (int pass = 0; pass < 40 && clean < 5; ++pass) {
    const std::int64_t retried = opt.executor->stats().retried_blocks;
    const EStepStatistics s = there.statistics(policy, model, 5);
    EXPECT_EQ(s.counts, here.counts) << pass;
    EXPECT_EQ(s.log_likelihood, here.log_likelihood) << pass;
    clean = opt.executor->stats().retried_blocks == retried ? clean + 1 : 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(400));  // heartbeats come
  }
  EXPECT_EQ(clean, 5) << "blocks were still re-asked after 40 passes";
  EXPECT_EQ(small.worker().trajectories_held(), 0);
  EXPECT_EQ(able.worker().trajectories_held(), 40);
}

void each_worker_is_sent_only_its_share(std::int64_t window) {
  Task t = task();
  Rng rng(11);
  t.task = make_gridworld_task({}, 256, 10, rng);
  GridworldObservationOptions options;
  options.per_step = 6;
  t.observed = observe_gridworld(t.task.mdp, t.task.trajectories, gridworld_subject_observation_model(5, 1.0),
                                 random_confounder_observation_model(3, rng), options, rng)
                   .trajectories;
  auto hub = std::make_shared<MemoryHub>();
  std::vector<std::unique_ptr<TaskWorker>> workers;
  for (int w = 0; w < 4; ++w) workers.push_back(std::make_unique<TaskWorker>(hub, "sampler-" + std::to_string(w)));
  BusExecutorOptions executor_options;
  executor_options.send_window_bytes = window;
  Optimiser opt(hub, executor_options, t);
  ASSERT_EQ(opt.executor->wait_for_workers(4, 10000), 4);
  ObservationEStepOptions remote;
  remote.executor = opt.executor;
  const ObservationEStep there(t.task.mdp, t.observed, t.prior, remote);
  const ObservationEStep estep(t.task.mdp, t.observed, t.prior);
  const ObservationModel model = dirichlet_mean(t.prior);
  for (int pass = 0; pass < 4; ++pass) {
    const Eigen::Vector4d theta(0.3 * pass, -0.2, 0.1, 0.5 + 0.1 * pass);
    const SoftSolution policy = soft_value_iteration(t.task.mdp, t.task.mdp.reward(theta));
    const EStepStatistics a = there.statistics(policy, model, 5), b = estep.statistics(policy, model, 5);
    EXPECT_EQ(a.counts, b.counts) << pass;
    EXPECT_EQ(a.alpha_dot.subject, b.alpha_dot.subject) << pass;
    EXPECT_EQ(a.alpha_dot.confounders, b.alpha_dot.confounders) << pass;
    EXPECT_EQ(a.log_likelihood, b.log_likelihood) << pass;
  }
  // The whole data set as the workers are sent it: one message per trajectory.
  std::int64_t whole = 0;
  for (size_t i = 0; i < estep.trajectories().size(); ++i) {
    whole += to_message(estep.trajectories()[i], static_cast<int>(i), 256, 0, "sampler-0").getEncodedSize();
  }
  const auto stats = opt.executor->stats();
  EXPECT_EQ(stats.local_blocks, 0);
  EXPECT_EQ(stats.trajectories_sent, 256) << "every trajectory sent once for all passes";
  EXPECT_EQ(stats.bytes_sent, whole);
  for (const auto& w : workers) {
    const double share = static_cast<double>(w->worker().trajectory_bytes_received()) / static_cast<double>(whole);
    EXPECT_GT(share, 0.2) << w->worker().id();
    EXPECT_LT(share, 0.3) << w->worker().id();
    EXPECT_EQ(w->worker().trajectories_held(), 64) << w->worker().id();
  }
}

// 256 trajectories (16 blocks) and four workers: each worker is sent its quarter of the
// data set's bytes, once for all passes (blocks stay with their worker from pass to
// pass), holds only those trajectories, and every pass is bit-identical to the pass in one
// process (theta with four workers: SameThetaWithOneTwoOrFourWorkers) -- with the default
// send window and with one so small that one block at a time is in flight.
TEST(EStepService, EachWorkerIsSentOnlyItsShare) {
  for (const std::int64_t window : {BusExecutorOptions{}.send_window_bytes, std::int64_t{1}}) {
    SCOPED_TRACE("send window " + std::to_string(window));
    each_worker_is_sent_only_its_share(window);
  }
}

}  // namespace
}  // namespace hbirl::services
