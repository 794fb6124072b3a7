#include "services/labeller_service.hpp"
#include "services/optimiser.hpp"
#include "services/perception_service.hpp"
#include "expect_refused.hpp"
#include "perception/labeller.hpp"
#include "sim_driver/simulator/simulator_service.hpp"

#include <gtest/gtest.h>

#include <functional>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <cmath>
#include "perception/image_codec.hpp"
#include <thread>
#include <unistd.h>

#include "experiments/onion_data.hpp"
#include "learner/input_error.hpp"
#include "services/keyed_bus.hpp"
#include "services/log_bus.hpp"
#include "services/memory_bus.hpp"
#include "services/process.hpp"
#include "services/recording_watch.hpp"
#include "service_threads.hpp"
#include "sim_driver/onion/onion.hpp"
#include "sim_driver/file/recorded_run.hpp"

namespace hbirl::services {
namespace {

using testing::quiet;
using testing::ServiceThread;
using testing::WorkerThread;

// The onion domain's camera, as hbirl-labeller takes it from the registry.
perception::CameraView onion_camera() { return *builtin_domain("onion")->camera(); }

SimulatorOptions small_run() {
  SimulatorOptions o;
  o.simulation.scene.fps = 5;  // 10 frames per step: a short run
  o.simulation.controlled_sorts = 6;
  o.simulation.sorts = 4;
  o.simulation.seed = 3;
  o.max_frames_per_second = 0;
  return o;
}

// The simulator publishes the run once the optimiser listens, then serves FRAME_REQUEST
// until the optimiser is done; returns what the optimiser learned (and how many frames
// the simulator sent again).
// `configure` sets further options; `log` hears what the optimiser says.
std::optional<OptimiserResult> run_serving_requests(std::shared_ptr<MemoryHub> hub, const Domain& domain,
                                                    const SimulatorOptions& run, int resend_after_ms,
                                                    std::int64_t* resent = nullptr,
                                                    const std::function<void(OptimiserOptions&)>& configure = nullptr,
                                                    const std::function<void(const std::string&)>& log = nullptr) {
  MemoryBus sim_bus(hub);
  Counters sim_counters = quiet("sim_driver");
  Simulator driver(sim_bus, domain, run, sim_counters);
  std::atomic<bool> done{false};
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    driver.publish_run(nullptr);
    driver.serve_until_learned([&done] { return done.load(); });  // FRAME_REQUEST served, END_RUN repeated
  });
  MemoryBus opt_bus(hub);
  Counters opt_counters = quiet("optimiser");
  OptimiserOptions options;
  options.resend_after_ms = resend_after_ms;
  if (configure) configure(options);
  auto result = run_optimiser(opt_bus, options, opt_counters, nullptr, log, [&] { listening.set_value(); });
  done = true;
  sim.join();
  if (resent) *resent = driver.frames_resent();
  return result;
}

// lcm-logger on a memory hub: every message to a recording, as it comes, except those
// `lose` picks, if given (a logger whose socket overflowed; it cannot ask for them again).
class Recorder {
 public:
  Recorder(std::shared_ptr<MemoryHub> hub, const std::string& path,
           std::function<bool(const std::string&, const std::uint8_t*, int)> lose = nullptr)
      : bus_(std::move(hub)), log_(path, "w"), lose_(std::move(lose)) {
    bus_.subscribe(
        ".*",
        [this](const Message& m) {
          if (lose_ && lose_(m.channel, m.data, m.size)) {
            ++lost_;
            return;
          }
          lcm::LogEvent e;
          e.timestamp = m.recv_utime;
          e.channel = m.channel;
          e.datalen = m.size;
          e.data = const_cast<std::uint8_t*>(m.data);
          log_.writeEvent(&e);
          std::fflush(log_.getFilePtr());  // lcm-logger flushes every 100 ms; the reader follows
        },
        1 << 20);  // only what `lose` picks is lost
    thread_ = std::thread([this] {
      while (!done_) bus_.handle(10);
    });
  }
  ~Recorder() { stop(); }
  void stop() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
  }
  int lost() const { return lost_; }
  bool good() { return log_.good(); }

 private:
  MemoryBus bus_;
  lcm::LogFile log_;
  std::function<bool(const std::string&, const std::uint8_t*, int)> lose_;
  std::atomic<bool> done_{false};
  std::atomic<int> lost_{0};
  std::thread thread_;
};

// The whole onion pipeline in one process, each service on its own endpoint and thread:
// camera frames (PNG) -> perception -> labeller -> optimiser with two sampler workers.
// Everything the live run records also comes back from the log.
TEST(Pipeline, OnionFromFramesToRewardAndFromItsLog) {
  const SimulatorOptions run = small_run();
  const Mdp mdp = onion::make_onion_mdp();
  auto hub = std::make_shared<MemoryHub>();
  const std::filesystem::path log_path =
      std::filesystem::temp_directory_path() / ("hbirl_pipeline_" + std::to_string(::getpid()) + ".lcmlog");
  std::optional<OptimiserResult> live;
  {
    Recorder recorder(hub, log_path.string());  // every message, as lcm-logger would write it
    ASSERT_TRUE(recorder.good());
    ServiceThread<PerceptionService> perception(hub, "perception");
    ServiceThread<LabellerService> labeller(hub, "labeller", onion_camera());
    WorkerThread w1(hub, "sampler-1"), w2(hub, "sampler-2");
    MemoryBus sim_bus(hub);
    Counters sim_counters = quiet("sim_driver");
    std::promise<void> listening;
    std::thread sim([&] {
      listening.get_future().wait();  // the optimiser must hear the run from its first message
      run_simulator(sim_bus, *builtin_domain("onion"), run, sim_counters, nullptr);
    });
    MemoryBus opt_bus(hub);
    Counters opt_counters = quiet("optimiser");
    OptimiserOptions options;
    options.workers = 2;
    live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
    sim.join();
    recorder.stop();
    ASSERT_TRUE(live.has_value());
    EXPECT_EQ(live->workers, 2);
    EXPECT_EQ(live->missing_frames, 0);
    EXPECT_GT(live->estep.remote_blocks, 0);
    perception.stop();
    labeller.stop();
    EXPECT_EQ(perception.counters().bad_messages, 0);
    EXPECT_EQ(labeller.counters().bad_messages, 0);
    EXPECT_EQ(opt_counters.gaps, 0);
  }
  // Independent truth for the data: the same sorts rendered, perceived and labelled in
  // one process, without the bus, give the same observations bit for bit.
  onion::SceneConfig controlled = onion::SceneConfig::controlled();
  controlled.fps = run.simulation.scene.fps;
  onion::DemonstrationOptions controlled_sorts;
  controlled_sorts.sorts = run.simulation.controlled_sorts;
  controlled_sorts.rule_contexts = true;  // as the labeller service gives them
  const onion::OnionDemonstration c = onion::demonstrate(mdp, controlled, controlled_sorts, run.simulation.seed + 1);
  double end = 0.0;
  for (const auto& t : c.truth) end += static_cast<double>(t.size()) * run.simulation.scene.step_seconds;
  onion::DemonstrationOptions demo_sorts;
  demo_sorts.sorts = run.simulation.sorts;
  demo_sorts.start_time = end;
  demo_sorts.rule_contexts = true;
  const onion::OnionDemonstration d = onion::demonstrate(mdp, run.simulation.scene, demo_sorts, run.simulation.seed);
  EXPECT_EQ(dataset_digest(live->data.observed), dataset_digest(d.observed));
  EXPECT_EQ(dataset_digest(live->data.controlled_observed), dataset_digest(c.observed));
  EXPECT_EQ(live->data.truth, d.truth);
  // Learned: the sorting rule (ILE 0 from 4 sorts with plausible eta, as in the paper-
  // scale experiment), and the same theta as learning on the one-process data.
  ASSERT_TRUE(live->learned.ile.has_value());
  EXPECT_LT(*live->learned.ile, 1e-9);
  Dataset same = live->data;
  same.observed = d.observed;
  same.controlled_observed = c.observed;
  const Learned local = learn_from_dataset(*builtin_domain("onion"), same, app::LearnSettings{});
  for (int k = 0; k < 4; ++k) EXPECT_EQ(live->learned.theta[k], local.theta[k]) << k;
  // Eta was learned per labeller rule, over the bus as here: the same learned eta.
  ASSERT_FALSE(live->data.observed[0].contexts.empty());
  ASSERT_TRUE(live->learned.eta.has_value());
  ASSERT_TRUE(local.eta.has_value());
  EXPECT_LE(live->learned.eta->learned.rows(), perception::kNumRules);
  EXPECT_EQ(live->learned.eta->learned, local.eta->learned);
  // The recorded log replays to the same data and the same theta.
  Counters replay_counters = quiet("replay");
  const OptimiserResult replay = learn_from_log({log_path.string(), "", false}, app::LearnSettings{}, replay_counters);
  EXPECT_EQ(replay.learned.digest, live->learned.digest);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(replay.learned.theta[k], live->learned.theta[k]) << k;
  ASSERT_TRUE(replay.learned.eta.has_value());
  EXPECT_EQ(replay.learned.eta->learned, live->learned.eta->learned);
  std::filesystem::remove(log_path);
}

// Camera frames lost on the way (every 6th, and again when sent again): the optimiser asks
// for them (FRAME_REQUEST), the simulator renders them again, and the data set is the
// same as without loss.
// A run no frame of which came (perception stopped at once, learned from with
// --allow-incomplete: no perception or labeller here): the episodes are there, their
// observations are not. The optimiser learns what the prior and the controlled run say,
// and says what is missing, whether it was told the domain (as the service is) or not.
TEST(Pipeline, ARunWithoutObservationsIsLearnedFromWhenAllowed) {
  SimulatorOptions run = small_run();
  run.simulation.controlled_sorts = 2;
  run.simulation.sorts = 2;
  for (const bool told : {true, false}) {
    auto hub = std::make_shared<MemoryHub>();
    MemoryBus sim_bus(hub);
    Counters sim_counters = quiet("sim_driver");
    Simulator driver(sim_bus, *builtin_domain("onion"), run, sim_counters);
    std::promise<void> listening;
    std::atomic<bool> done{false};
    std::thread sim([&] {
      listening.get_future().wait();
      driver.publish_run(nullptr);
      while (!done) sim_bus.handle(20);
    });
    MemoryBus opt_bus(hub);
    Counters opt_counters = quiet("optimiser");
    OptimiserOptions options;
    if (told) options.domain = builtin_domain("onion");
    options.allow_incomplete = true;
    options.quiet_ms = 200;
    options.resend_after_ms = 50;
    const auto live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
    done = true;
    sim.join();
    ASSERT_TRUE(live.has_value()) << told;
    EXPECT_NE(live->incomplete.find("frame(s)"), std::string::npos) << live->incomplete;
    EXPECT_EQ(live->data.observed.size(), 2u);
    EXPECT_EQ(live->data.num_symbols, builtin_domain("onion")->num_symbols());
    EXPECT_TRUE(live->learned.theta.allFinite()) << told;
  }
}

TEST(Pipeline, LostFramesAreAskedForAgain) {
  const SimulatorOptions run = small_run();
  const Mdp mdp = onion::make_onion_mdp();
  auto hub = std::make_shared<MemoryHub>();
  hub->set_loss([](const std::string& channel, const std::uint8_t* data, int size) {
    if (channel != channels::kCamera.name) return false;
    hbirl::camera_frame_t f;
    return f.decode(data, 0, size) > 0 && f.seq % 6 == 0;
  });
  ServiceThread<PerceptionService> perception(hub, "perception");
  ServiceThread<LabellerService> labeller(hub, "labeller", onion_camera());
  std::int64_t resent = 0;
  const auto live = run_serving_requests(hub, *builtin_domain("onion"), run, 200, &resent);
  ASSERT_TRUE(live.has_value());
  EXPECT_GT(hub->dropped(), 0);
  EXPECT_GT(live->frame_requests, 0);
  EXPECT_GT(resent, 0);
  EXPECT_EQ(live->missing_frames, 0);
  onion::DemonstrationOptions demo_sorts;
  demo_sorts.sorts = run.simulation.sorts;
  demo_sorts.start_time = 0.0;
  demo_sorts.rule_contexts = true;  // as the labeller service gives them
  onion::SceneConfig controlled = onion::SceneConfig::controlled();
  controlled.fps = run.simulation.scene.fps;
  onion::DemonstrationOptions controlled_sorts;
  controlled_sorts.sorts = run.simulation.controlled_sorts;
  controlled_sorts.rule_contexts = true;
  const onion::OnionDemonstration c = onion::demonstrate(mdp, controlled, controlled_sorts, run.simulation.seed + 1);
  for (const auto& t : c.truth)
    demo_sorts.start_time += static_cast<double>(t.size()) * run.simulation.scene.step_seconds;
  EXPECT_EQ(dataset_digest(live->data.observed),
            dataset_digest(onion::demonstrate(mdp, run.simulation.scene, demo_sorts, run.simulation.seed).observed));
  EXPECT_EQ(dataset_digest(live->data.controlled_observed), dataset_digest(c.observed))
      << live->data.controlled_observed.size() << " controlled episodes (" << live->data.skipped_controlled
      << " left out) vs " << c.observed.size();
}

SimulatorOptions gridworld_run(std::uint64_t seed, int trajectories, int controlled) {
  SimulatorOptions run;
  run.simulation.seed = seed;
  run.max_frames_per_second = 0;
  run.simulation.trajectories = trajectories;
  run.simulation.controlled_trajectories = controlled;
  return run;
}

// The paper's Gridworld over the bus: its simulator publishes the observations itself
// (no camera), two sampler workers do the E-step. Checked against what the simulator was
// asked for (episodes, steps, observations per step, eta of the controlled run), against
// learning on the same data in one process (same bits), and against the true goal.
TEST(Pipeline, GridworldFromSimulatorToReward) {
  SimulatorOptions run = gridworld_run(5, 20, 10);
  run.simulation.confounders = 3;
  const Mdp mdp = builtin_domain("gridworld")->mdp();
  auto hub = std::make_shared<MemoryHub>();
  WorkerThread w1(hub, "sampler-1"), w2(hub, "sampler-2");
  MemoryBus sim_bus(hub);
  Counters sim_counters = quiet("sim_driver");
  Simulator driver(sim_bus, *builtin_domain("gridworld"), run, sim_counters);
  EXPECT_EQ(driver.listeners(), std::vector<std::string>{"optimiser"});
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    driver.publish_run(nullptr);
  });
  MemoryBus opt_bus(hub);
  Counters opt_counters = quiet("optimiser");
  OptimiserOptions options;
  options.workers = 2;
  const auto live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
  sim.join();
  ASSERT_TRUE(live.has_value());
  EXPECT_EQ(live->data.domain, "gridworld");
  EXPECT_EQ(live->missing_frames, 0);
  EXPECT_EQ(opt_counters.bad_messages, 0);
  EXPECT_GT(live->estep.remote_blocks, 0);
  std::int64_t answered = 0;  // the result's workers_answered: by worker, all of the remote blocks
  for (const auto& [worker, blocks] : live->estep.blocks_by_worker) {
    EXPECT_TRUE(worker == "sampler-1" || worker == "sampler-2") << worker;
    answered += blocks;
  }
  EXPECT_EQ(answered, live->estep.remote_blocks);
  ASSERT_EQ(live->data.observed.size(), 20u);
  ASSERT_EQ(live->data.controlled_observed.size(), 10u);
  ASSERT_EQ(live->data.truth.size(), 20u);
  EXPECT_EQ(live->data.num_sources, 4);
  for (const auto& t : live->data.observed) {
    ASSERT_EQ(t.length(), 10);
    for (int step = 0; step < 10; ++step) EXPECT_EQ(t.observations_at(step), 40);
    EXPECT_FALSE(t.ends_in_terminal);
  }
  for (const auto& t : live->data.controlled_observed) {  // the subject alone
    EXPECT_EQ(t.eta.col(0).minCoeff(), 1.0);
    EXPECT_EQ(t.eta.rightCols(3).maxCoeff(), 0.0);
  }
  // Plausible eta: 0.6 on the favoured source, 0.4/3 on each other.
  EXPECT_NEAR(live->data.observed[0].eta.row(0).maxCoeff(), 0.6, 1e-12);
  ASSERT_TRUE(live->data.true_weights.has_value());
  EXPECT_EQ(live->data.true_weights->sum(), 1.0);  // one goal corner
  // Same bits as learning in one process; the goal corner is the learned reward's best.
  const Learned local = learn_from_dataset(*builtin_domain("gridworld"), live->data, app::LearnSettings{});
  for (int k = 0; k < 4; ++k) EXPECT_EQ(live->learned.theta[k], local.theta[k]) << k;
  Eigen::Index goal = 0, best = 0;
  live->data.true_weights->maxCoeff(&goal);
  live->learned.theta.maxCoeff(&best);
  EXPECT_EQ(best, goal);
  ASSERT_TRUE(live->learned.ile.has_value());
  EXPECT_LT(*live->learned.ile, 0.5) << "theta " << live->learned.theta.transpose();
}

// Learning while it watches (--anytime): one ESTIMATE per demonstration as the run goes
// on, each what learn_from_dataset gives on the demonstrations so far started also from the
// one before (bit for bit), with a confidence; the final REWARD as without it.
TEST(Pipeline, AnEstimateAfterEachDemonstration) {
  const SimulatorOptions run = gridworld_run(7, 5, 5);
  const std::shared_ptr<const Domain> domain = builtin_domain("gridworld");
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus sim_bus(hub), opt_bus(hub), listener(hub);
  Counters sim_counters = quiet("sim_driver"), opt_counters = quiet("optimiser"), heard = quiet("listener");
  std::vector<hbirl::estimate_t> on_bus;
  Subscriptions subs;
  subs.add(listener, subscribe(listener, channels::kEstimate, heard,
                               [&](const hbirl::estimate_t& e, const Message&) { on_bus.push_back(e); }));
  Simulator driver(sim_bus, *domain, run, sim_counters);
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    driver.publish_run(nullptr);
  });
  OptimiserOptions options;
  options.anytime = true;
  options.learning.posterior.samples = 30;
  const auto live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
  sim.join();
  while (listener.handle(0) > 0) {
  }
  ASSERT_TRUE(live.has_value());
  ASSERT_EQ(live->estimates.size(), 5u);
  EXPECT_EQ(on_bus.size(), 5u);
  EXPECT_EQ(heard.bad_messages, 0);
  app::LearnSettings settings = options.learning;
  for (size_t k = 0; k < live->estimates.size(); ++k) {
    const hbirl::estimate_t& e = live->estimates[k];
    EXPECT_EQ(e.demonstrations, static_cast<int>(k) + 1);
    const Dataset first = first_demonstrations(live->data, k + 1);
    const Learned expected = learn_from_dataset(*domain, first, settings);
    ASSERT_EQ(e.theta.size(), static_cast<size_t>(expected.theta.size()));
    for (size_t i = 0; i < e.theta.size(); ++i) EXPECT_EQ(e.theta[i], expected.theta[static_cast<Eigen::Index>(i)]);
    ASSERT_TRUE(expected.confidence.has_value());
    EXPECT_EQ(e.confidence, *expected.confidence);
    EXPECT_GE(e.ile, 0.0);  // the gridworld's true weights are known
    settings.em.warm_start = expected.theta;
  }
  const Learned local = learn_from_dataset(*domain, live->data, app::LearnSettings{});
  EXPECT_EQ(live->learned.theta, local.theta);
}

// Knowing when it has seen enough: once the rule holds the optimiser sends STOP, the
// simulator ends the run after the episode under way (END_RUN stating what it published),
// and the run is learned from, complete. (A rule nearly any estimate meets, so the test
// does not hang on the domain's confidence; where it stops depends on timing.)
TEST(Pipeline, StopAtConfidenceEndsTheRunEarly) {
  SimulatorOptions run = gridworld_run(9, 40, 5);
  // A sensor in real time: the whole run takes 10 s, so the first two estimates come well
  // before its end even under the sanitizers on a loaded machine (at 300 frames/s they did
  // not, once: 40 of 40 episodes); the run stops after a few episodes anyway.
  run.max_frames_per_second = 20;
  const std::shared_ptr<const Domain> domain = builtin_domain("gridworld");
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus sim_bus(hub), opt_bus(hub);
  Counters sim_counters = quiet("sim_driver"), opt_counters = quiet("optimiser");
  Simulator driver(sim_bus, *domain, run, sim_counters);
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    driver.publish_run(nullptr, [&] { sim_bus.handle(0); });  // hears STOP between frames
  });
  OptimiserOptions options;
  options.anytime = true;
  options.stop_at_confidence = 1e-9;
  options.stop_after = 2;
  options.learning.posterior.samples = 20;
  const auto live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
  sim.join();
  ASSERT_TRUE(live.has_value());
  EXPECT_EQ(live->stop_sent_after, 2);
  EXPECT_GE(live->data.observed.size(), 2u);
  EXPECT_LT(live->data.observed.size(), 40u) << "the run did not stop early";
  EXPECT_EQ(live->missing_frames, 0);
  EXPECT_TRUE(live->incomplete.empty());
  EXPECT_EQ(sim_counters.bad_messages, 0);
}

// Any size of Gridworld is a domain (--domain gridworld --size 10): the simulator, the
// markers (named gridworld:10), the workers (sent the 100-state MDP over the bus) and the
// optimiser agree on it, and the learned reward's best corner is the goal.
TEST(Pipeline, GridworldOfSizeTenLearnsTheGoal) {
  DomainOptions ten;
  ten.gridworld_size = 10;
  const std::shared_ptr<const Domain> domain = open_domain("gridworld", ten);
  SimulatorOptions run = gridworld_run(3, 30, 15);
  run.simulation.length = 25;  // corner to corner is 18 moves
  run.simulation.confounders = 1;
  auto hub = std::make_shared<MemoryHub>();
  WorkerThread worker(hub, "sampler-1");
  MemoryBus sim_bus(hub);
  Counters sim_counters = quiet("sim_driver");
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    run_simulator(sim_bus, *domain, run, sim_counters, nullptr);
  });
  MemoryBus opt_bus(hub);
  Counters opt_counters = quiet("optimiser");
  OptimiserOptions options;
  options.workers = 1;
  const auto live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
  sim.join();
  ASSERT_TRUE(live.has_value());
  EXPECT_EQ(live->data.domain, "gridworld:10");
  EXPECT_EQ(live->workers, 1);
  EXPECT_GT(live->estep.remote_blocks, 0);
  EXPECT_EQ(worker.worker().mdp_digest(), dynamics_digest(domain->mdp()));
  ASSERT_TRUE(live->data.true_weights.has_value());
  Eigen::Index goal = 0, best = 0;
  live->data.true_weights->maxCoeff(&goal);
  live->learned.theta.maxCoeff(&best);
  EXPECT_EQ(best, goal) << "theta " << live->learned.theta.transpose();
}

// Ground truth lost on the way (every 5th message, and again when sent again): the
// controlled run's prior needs every step's, so the optimiser asks for those steps again
// and learns exactly what it learns without loss.
TEST(Pipeline, LostGroundTruthIsAskedForAgain) {
  const Mdp mdp = builtin_domain("gridworld")->mdp();
  const auto run_with = [&](bool lossy) {
    auto hub = std::make_shared<MemoryHub>();
    if (lossy) {
      hub->set_loss([](const std::string& channel, const std::uint8_t* data, int size) {
        if (channel != channels::kGroundTruth.name) return false;
        hbirl::ground_truth_t t;
        return t.decode(data, 0, size) > 0 && t.seq % 5 == 0;
      });
    }
    auto result = run_serving_requests(hub, *builtin_domain("gridworld"), gridworld_run(11, 6, 5), 100);
    EXPECT_EQ(hub->dropped() > 0, lossy);
    EXPECT_EQ(result->frame_requests > 0, lossy);
    return *result;
  };
  const OptimiserResult clean = run_with(false), lossy = run_with(true);
  EXPECT_EQ(lossy.data.skipped_controlled, 0);
  ASSERT_EQ(lossy.data.controlled_truth.size(), 5u);
  EXPECT_EQ(lossy.data.controlled_truth, clean.data.controlled_truth);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(lossy.learned.theta[k], clean.learned.theta[k]) << k;
}

// A recording is complete whenever the run is: observations the logger alone lost (the
// optimiser had them all) are asked for again until the recording holds them, and the
// recording then gives the live data set; without --recording it lacks them. A logger
// that never records them again is given up on after recording_patience_ms, and the run
// is learned from all the same.
TEST(Pipeline, WhatTheRecordingLostIsAskedForAgain) {
  const auto tmp = std::filesystem::temp_directory_path() / ("hbirl_rec_" + std::to_string(::getpid()));
  std::filesystem::create_directories(tmp);
  const auto run_with = [&](bool watch, bool lose_for_good, const std::string& name) {
    auto hub = std::make_shared<MemoryHub>();
    std::set<std::pair<int, int>> lost_once;
    std::mutex lost_mutex;
    const std::string path = (tmp / name).string();
    Recorder recorder(hub, path, [&](const std::string& channel, const std::uint8_t* data, int size) {
      if (channel != channels::kObservations.name) return false;
      hbirl::observations_t o;
      if (o.decode(data, 0, size) <= 0 || (o.episode * 7 + o.step) % 5 != 0) return false;
      std::lock_guard<std::mutex> lock(lost_mutex);
      return lost_once.insert({o.episode, o.step}).second || lose_for_good;
    });
    std::int64_t resent = 0;
    std::string said;
    auto live = run_serving_requests(
        hub, *builtin_domain("gridworld"), gridworld_run(13, 6, 5), 100, &resent,
        [&](OptimiserOptions& options) {
          options.recording_patience_ms = 500;
          options.confirm_ms = 100;
          if (watch) options.recording.path = path;
        },
        [&said](const std::string& s) { said += s + "\n"; });
    recorder.stop();
    EXPECT_GT(recorder.lost(), 0);
    EXPECT_EQ(resent > 0, watch);
    return std::make_tuple(*live, path, said);
  };
  const auto [unwatched, unwatched_path, unwatched_said] = run_with(false, false, "unwatched.lcmlog");
  EXPECT_EQ(unwatched.missing_frames, 0);
  try {
    Counters c;
    collect_from_log({unwatched_path, "", false}, c);
    ADD_FAILURE() << "a recording that lacks frames was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("frame(s) missing"), std::string::npos) << e.what();
  }

  const auto [watched, watched_path, watched_said] = run_with(true, false, "watched.lcmlog");
  EXPECT_NE(watched_said.find("the recording holds the whole run now"), std::string::npos) << watched_said;
  EXPECT_EQ(watched.recording, "complete");
  EXPECT_EQ(unwatched.recording, "");
  Counters counters;
  const OptimiserResult read = collect_from_log({watched_path, "", false}, counters);
  EXPECT_EQ(read.incomplete, "");
  EXPECT_EQ(dataset_digest(read.data.observed), dataset_digest(watched.data.observed));
  EXPECT_EQ(dataset_digest(read.data.controlled_observed), dataset_digest(watched.data.controlled_observed));
  EXPECT_EQ(dataset_digest(watched.data.observed), dataset_digest(unwatched.data.observed));  // the same run
  for (int k = 0; k < 4; ++k) EXPECT_EQ(watched.learned.theta[k], unwatched.learned.theta[k]) << k;

  // A recording that never appears (lcm-logger died at once) is given up on too.
  const auto never = run_serving_requests(std::make_shared<MemoryHub>(), *builtin_domain("gridworld"),
                                          gridworld_run(13, 6, 5), 100, nullptr, [&](OptimiserOptions& options) {
                                            options.recording_patience_ms = 300;
                                            options.confirm_ms = 100;
                                            options.recording.path = (tmp / "never_written.lcmlog").string();
                                          });
  ASSERT_TRUE(never.has_value());
  EXPECT_EQ(never->recording, "lacks everything: the file is not there");

  const auto [given_up, given_up_path, given_up_said] = run_with(true, true, "given_up.lcmlog");
  EXPECT_NE(given_up_said.find("which did not come again (lcm-logger stopped?)"), std::string::npos) << given_up_said;
  EXPECT_EQ(given_up.recording.rfind("lacks 0 episode end(s), ", 0), 0u) << given_up.recording;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(given_up.learned.theta[k], unwatched.learned.theta[k]) << k;
  std::filesystem::remove_all(tmp);
}

// The run's REWARD that the logger lost (LCM drops what comes faster than lcm-logger reads,
// and the end of learning is a burst) is published again, once what came after it is
// recorded, until the recording holds it, so that its readers see a finished run; a logger
// that never records it is given up on after 30 sendings, and said. Either way the run's
// theta is the same.
TEST(Pipeline, TheRewardTheRecordingLostIsPublishedAgain) {
  const auto tmp = std::filesystem::temp_directory_path() / ("hbirl_reward_" + std::to_string(::getpid()));
  std::filesystem::create_directories(tmp);
  const auto run_with = [&](bool lose_for_good, const std::string& name) {
    auto hub = std::make_shared<MemoryHub>();
    const std::string path = (tmp / name).string();
    std::atomic<int> rewards{0};
    Recorder recorder(hub, path, [&](const std::string& channel, const std::uint8_t*, int) {
      return channel == channels::kReward.name && (rewards++ == 0 || lose_for_good);
    });
    // Another service's heartbeat: what reaches the logger after the REWARD shows it lost.
    std::atomic<bool> done{false};
    std::thread heartbeat([&] {
      MemoryBus bus(hub);
      const std::uint8_t beat = 1;
      for (; !done; std::this_thread::sleep_for(std::chrono::milliseconds(20))) bus.publish("BEAT", &beat, 1);
    });
    std::string said;
    const auto live = run_serving_requests(
        hub, *builtin_domain("gridworld"), gridworld_run(13, 6, 5), 100, nullptr,
        [&](OptimiserOptions& options) {
          options.recording_patience_ms = 500;
          options.confirm_ms = 100;
          options.recording.path = path;
        },
        [&said](const std::string& s) { said += s + "\n"; });
    done = true;
    heartbeat.join();
    recorder.stop();
    RecordingWatch watch(path, "", std::int64_t{1} << 30);
    watch.follow_rewards_only();
    watch.read(std::chrono::seconds(10));
    EXPECT_TRUE(watch.caught_up());
    EXPECT_EQ(watch.holds_reward(live->data.last_utime), !lose_for_good) << name;
    return std::make_tuple(*live, said, rewards.load());
  };
  const auto [once, once_said, once_published] = run_with(false, "reward_lost_once.lcmlog");
  EXPECT_NE(once_said.find("the recording holds the reward now"), std::string::npos) << once_said;
  EXPECT_EQ(once.recording, "complete");
  EXPECT_EQ(once_published, 2);  // sent again once, when it was lost; never while it was on its way

  const auto [never, never_said, never_published] = run_with(true, "reward_never_recorded.lcmlog");
  EXPECT_NE(never_said.find("lacks the run's reward (REWARD), though sent 30 times"), std::string::npos) << never_said;
  EXPECT_EQ(never.recording, "lacks the run's reward (REWARD)");
  EXPECT_EQ(never_published, 30);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(never.learned.theta[k], once.learned.theta[k]) << k;
  std::filesystem::remove_all(tmp);
}

// Asked to stop while it learns (SIGTERM in hbirl-optimiser), the optimiser stops at the
// next E-step -- also while waiting for a worker's answer -- publishes no reward and
// leaves the caller's bus without its subscriptions: the caller may go on handling it.
TEST(Pipeline, OptimiserStopsWhileLearningAndLeavesTheBusClean) {
  const Mdp mdp = builtin_domain("gridworld")->mdp();
  auto hub = std::make_shared<MemoryHub>();
  WorkerThread worker(hub, "sampler-1");
  MemoryBus sim_bus(hub), watch_bus(hub);
  Counters sim_counters = quiet("sim_driver"), watch_counters = quiet("watch");
  std::atomic<int> progress{0}, rewards{0};
  subscribe(watch_bus, channels::kEmProgress, watch_counters,
            [&](const hbirl::em_progress_t&, const Message&) { ++progress; });
  subscribe(watch_bus, channels::kReward, watch_counters, [&](const hbirl::reward_t&, const Message&) { ++rewards; });
  std::atomic<bool> done{false};
  std::thread watch([&] {
    while (!done) watch_bus.handle(10);
  });
  const SimulatorOptions run = gridworld_run(7, 8, 4);
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    run_simulator(sim_bus, *builtin_domain("gridworld"), run, sim_counters, nullptr);
  });
  MemoryBus opt_bus(hub);
  Counters opt_counters = quiet("optimiser");
  OptimiserOptions options;
  options.workers = 1;
  const auto stopped = run_optimiser(
      opt_bus, options, opt_counters, [&] { return progress >= 2; }, nullptr, [&] { listening.set_value(); });
  sim.join();
  EXPECT_FALSE(stopped.has_value());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the watcher hears the last of it
  const int iterations_before_stop = progress;
  EXPECT_GE(iterations_before_stop, 2);
  // The run again on the same bus: the old optimiser's handlers are gone (under the
  // sanitizers, a handler of the dead data set builder or executor would be caught).
  std::promise<void> again;
  std::thread sim2([&] {
    again.get_future().wait();
    run_simulator(sim_bus, *builtin_domain("gridworld"), run, sim_counters, nullptr);
  });
  const auto learned = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { again.set_value(); });
  sim2.join();
  done = true;
  watch.join();
  ASSERT_TRUE(learned.has_value());
  EXPECT_EQ(learned->data.observed.size(), 8u);
  EXPECT_EQ(rewards, 1);
  EXPECT_LT(iterations_before_stop, learned->learned.em_iterations) << "the first run did not stop early";
}

// Ground truth is checked field by field; true weights that disagree mid-run leave the
// ILE unknown but keep the true steps (the controlled run's prior needs them).
// Made-up frames under ever new (episode, step, frame) keys cannot grow the optimiser's
// data set past its limit (--max-dataset-mb): the frames beyond it are refused, naming
// the option, and not kept; repeats of kept frames still pass as repeats.
// A sensor's contexts (the labeller's rules) are kept per observation; a context count
// that is not 0 or n and a context out of range are refused naming the field. Contexts
// are all or none over the demonstrations: when some frames gave them and others not
// (a forged frame, a sensor that gives them in part of the run) none are kept, and the
// data set says so -- a frame cannot decide it for the whole run.
TEST(DatasetBuilder, ContextsAreAllOrNoneAndInRange) {
  const auto run = [](bool second_frame_with_contexts) {
    DatasetBuilder b;
    hbirl::episode_marker_t e{};
    e.domain = "test";
    e.episode = 0;
    e.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
    e.frames_per_step = 1;
    b.on_marker(e);
    hbirl::observations_t o{};
    o.num_symbols = 4;
    o.num_sources = 2;
    o.n = 2;
    o.symbol = {1, 2};
    o.eta = {{0.5, 0.5}, {0.9, 0.1}};
    o.num_context = 2;
    o.context = {3, 65535};
    b.on_observations(o);
    const auto refused = [&b](const hbirl::observations_t& m, const std::string& field) {
      hbirl::testing::expect_refused(
          [&] {  // as the bus hands it over (typed subscribe)
            validate(m);
            b.on_observations(m);
          },
          field);
    };
    o.step = 1;
    hbirl::observations_t bad = o;
    bad.num_context = 1;
    bad.context = {3};
    refused(bad, "observations.num_context");
    bad = o;
    bad.context[0] = 65536;
    refused(bad, "observations.context[0]");
    bad = o;
    bad.context[1] = -1;
    refused(bad, "observations.context[1]");
    if (!second_frame_with_contexts) {
      o.num_context = 0;
      o.context.clear();
    }
    b.on_observations(o);
    e.kind = hbirl::episode_marker_t::END_EPISODE;
    e.num_steps = 2;
    b.on_marker(e);
    return b.build();
  };
  const Dataset all = run(true);
  ASSERT_EQ(all.observed.size(), 1u);
  EXPECT_EQ(all.observed[0].contexts, (std::vector<int>{3, 65535, 3, 65535}));
  EXPECT_TRUE(all.contexts_note.empty());
  const Dataset some = run(false);
  ASSERT_EQ(some.observed.size(), 1u);
  EXPECT_TRUE(some.observed[0].contexts.empty());
  EXPECT_NE(some.contexts_note.find("contexts ignored"), std::string::npos) << some.contexts_note;
}

// (A tally, which keeps no observation, refuses the same frames: RecordingWatch says of a
// recording what its readers, full builders, will.)
TEST(DatasetBuilder, ObservationsBeyondTheLimitAreRefused) {
  for (const bool tally : {false, true}) {
    DatasetBuilder b;
    if (tally) b.tally_only();
    b.limit(64 * 1024);
    hbirl::observations_t o{};
    o.num_symbols = 4;
    o.num_sources = 2;
    o.n = 8;
    o.symbol.assign(8, 1);
    o.eta.assign(8, {0.5, 0.5});
    int kept = 0, refused = 0;
    for (int k = 0; k < 2000; ++k) {
      o.episode = k / 100;
      o.step = k % 100;
      try {
        b.on_observations(o);
        ++kept;
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--max-dataset-mb"), std::string::npos) << e.what();
        ++refused;
      }
    }
    EXPECT_EQ(kept, 64 * 1024 / (96 + 4 * 8 + 8 * 16)) << "tally " << tally;
    EXPECT_EQ(refused, 2000 - kept);
    o.episode = 0;
    o.step = 0;
    EXPECT_NO_THROW(b.on_observations(o));  // a repeat of a kept frame
  }
}

// A marker that relabels an episode (controlled run vs demonstration) after its first
// marker said otherwise is refused, naming the field; the first word stands.
// One frame of episode `episode` holding one observation: `symbol` with `eta` (over
// eta.size() sources) in a four-symbol alphabet.
hbirl::observations_t one_observation(int symbol, const std::vector<double>& eta, int episode = 0) {
  hbirl::observations_t o{};
  o.num_symbols = 4;
  o.num_sources = static_cast<std::int32_t>(eta.size());
  o.n = 1;
  o.symbol = {static_cast<std::int16_t>(symbol)};
  o.eta = {eta};
  o.episode = episode;
  return o;
}

TEST(DatasetBuilder, AMarkerCannotRelabelAnEpisode) {
  DatasetBuilder b;
  hbirl::episode_marker_t m{};
  m.domain = "gridworld";
  m.episode = 3;
  m.controlled = true;
  m.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
  m.frames_per_step = 1;
  b.on_marker(m);
  hbirl::episode_marker_t forged = m;
  forged.controlled = false;
  forged.kind = hbirl::episode_marker_t::END_EPISODE;
  forged.num_steps = 1;
  try {
    b.on_marker(forged);
    ADD_FAILURE() << "the relabelling marker was obeyed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "episode_marker.controlled");
  }
  m.kind = hbirl::episode_marker_t::END_EPISODE;
  m.num_steps = 1;
  EXPECT_NO_THROW(b.on_marker(m));  // the sensor's own end marker agrees
  // Refused, and the run contradicts itself (had the forged marker come first, the
  // sensor's would be the one refused: either way the optimiser fails the run).
  EXPECT_NE(b.contradiction().find("contradicts it"), std::string::npos) << b.contradiction();
}

// Two copies of one frame's observations, one step's ground truth or one episode's end
// that differ: one of them is not the sensor's (its services are deterministic), and the
// run contradicts itself -- a forger who is first no longer decides silently. Copies that
// agree (the simulator's repeats, frames sent again on request) are ignored.
TEST(DatasetBuilder, CopiesThatDisagreeContradictTheRun) {
  const hbirl::observations_t o = one_observation(2, {0.7, 0.3});
  hbirl::ground_truth_t t{};
  t.domain = "gridworld";
  t.state = 3;
  t.action = 1;
  hbirl::episode_marker_t end{};
  end.domain = "gridworld";
  end.kind = hbirl::episode_marker_t::END_EPISODE;
  end.num_steps = 1;
  end.frames_per_step = 1;
  {
    DatasetBuilder b;
    b.on_observations(o);
    b.on_observations(o);
    b.on_truth(t);
    b.on_truth(t);
    b.on_marker(end);
    b.on_marker(end);
    EXPECT_TRUE(b.contradiction().empty()) << b.contradiction();
  }
  {
    DatasetBuilder b;
    b.on_observations(o);
    hbirl::observations_t other = o;
    other.symbol = {1};
    b.on_observations(other);
    EXPECT_NE(b.contradiction().find("two different observations of episode 0, step 0, frame 0"), std::string::npos)
        << b.contradiction();
  }
  {
    DatasetBuilder b;
    b.on_observations(o);
    hbirl::observations_t other = o;
    other.eta = {{0.6, 0.4}};
    b.on_observations(other);
    EXPECT_FALSE(b.contradiction().empty());
  }
  {
    // A tally (RecordingWatch's) keeps only each frame's digest, no observation: a copy
    // that differs -- in eta, symbol or context -- contradicts it exactly as a full builder,
    // an identical one does not, nor one whose eta has -0 for 0 (equal to both), and it
    // has no data set to give.
    hbirl::observations_t first = one_observation(2, {1.0, 0.0});
    first.num_context = 1;
    first.context = {0};
    hbirl::observations_t other_eta = first, other_symbol = first, other_context = first, minus_zero = first;
    other_eta.eta = {{0.6, 0.4}};
    other_symbol.symbol = {1};
    other_context.context = {1};
    minus_zero.eta = {{1.0, -0.0}};
    for (const hbirl::observations_t* other : {&other_eta, &other_symbol, &other_context, &minus_zero}) {
      DatasetBuilder full, tally;
      tally.tally_only();
      for (DatasetBuilder* b : {&full, &tally}) {
        b->on_observations(first);
        b->on_observations(first);
        EXPECT_TRUE(b->contradiction().empty()) << b->contradiction();
        b->on_observations(*other);
      }
      EXPECT_EQ(tally.contradiction(), full.contradiction());
      EXPECT_EQ(full.contradiction().empty(), other == &minus_zero) << full.contradiction();
      EXPECT_EQ(full.held_observations(), 1);
      EXPECT_EQ(tally.held_observations(), 0);
      EXPECT_THROW((void)tally.build(), std::logic_error);
      EXPECT_THROW((void)tally.take(), std::logic_error);
      EXPECT_THROW(full.tally_only(), std::logic_error);  // too late: a frame is kept
    }
  }
  {
    DatasetBuilder b;
    b.on_truth(t);
    hbirl::ground_truth_t other = t;
    other.action = 0;
    b.on_truth(other);
    EXPECT_NE(b.contradiction().find("two different ground truths"), std::string::npos) << b.contradiction();
  }
  for (const auto& change : std::vector<std::function<void(hbirl::episode_marker_t&)>>{
           [](auto& m) { m.num_steps = 2; }, [](auto& m) { m.ends_in_terminal = true; },
           [](auto& m) { m.frames_per_step = 2; }}) {
    DatasetBuilder b;
    b.on_marker(end);
    hbirl::episode_marker_t other = end;
    change(other);
    b.on_marker(other);
    EXPECT_NE(b.contradiction().find("ended twice, differently"), std::string::npos) << b.contradiction();
  }
  // The forger first, the sensor's copies only once the data set is taken (the optimiser
  // learning): still compared, with the digests of what was taken.
  hbirl::episode_marker_t end_run = end;
  end_run.kind = hbirl::episode_marker_t::END_RUN;
  end_run.num_steps = 1;
  const auto taken = [&](const hbirl::observations_t& first) {
    auto b = std::make_unique<DatasetBuilder>();
    b->on_observations(first);
    b->on_truth(t);
    b->on_marker(end);
    b->on_marker(end_run);
    EXPECT_TRUE(b->complete());
    b->take();
    return b;
  };
  hbirl::observations_t forged = o;
  forged.symbol = {3};
  {
    auto b = taken(forged);
    b->on_observations(forged);  // a repeat of what was taken
    EXPECT_TRUE(b->contradiction().empty()) << b->contradiction();
    b->on_observations(o);  // the sensor's
    EXPECT_NE(b->contradiction().find("two different observations"), std::string::npos) << b->contradiction();
  }
  {
    auto b = taken(o);
    hbirl::ground_truth_t other = t;
    other.state = 0;
    b->on_truth(t);
    EXPECT_TRUE(b->contradiction().empty()) << b->contradiction();
    b->on_truth(other);
    EXPECT_NE(b->contradiction().find("two different ground truths"), std::string::npos) << b->contradiction();
  }
  {
    auto b = taken(o);
    b->on_marker(end);
    EXPECT_TRUE(b->contradiction().empty()) << b->contradiction();
    hbirl::episode_marker_t longer = end;
    longer.num_steps = 3;
    b->on_marker(longer);
    EXPECT_NE(b->contradiction().find("ended twice, differently"), std::string::npos) << b->contradiction();
  }
}

// Once END_RUN states how many episodes the run had, an episode beyond them (a stray
// sender's observations under a made-up episode id) neither holds the run up nor enters
// the data set; an END_RUN before any episode ended is not believed.
TEST(DatasetBuilder, EndRunStatesTheRunsEpisodes) {
  DatasetBuilder b;
  hbirl::episode_marker_t end_run{};
  end_run.domain = "gridworld";
  end_run.kind = hbirl::episode_marker_t::END_RUN;
  end_run.num_steps = 1;
  end_run.frames_per_step = 1;
  EXPECT_THROW(b.on_marker(end_run), InputError);            // before any episode ended
  hbirl::observations_t o = one_observation(2, {1.0}, 999);  // a stray sender's
  b.on_observations(o);
  o.episode = 0;
  b.on_observations(o);
  hbirl::episode_marker_t end{};
  end.domain = "gridworld";
  end.kind = hbirl::episode_marker_t::END_EPISODE;
  end.num_steps = 1;
  end.frames_per_step = 1;
  b.on_marker(end);
  EXPECT_FALSE(b.complete());
  b.on_marker(end_run);
  EXPECT_TRUE(b.complete());
  EXPECT_EQ(b.build().observed.size(), 1u);
  // ... but a run with an episode 999 cannot have had 1 episode: it contradicts itself.
  EXPECT_NE(b.contradiction().find("END_RUN of 1 episodes after a message about episode 999"), std::string::npos)
      << b.contradiction();
  end_run.num_steps = 2;
  EXPECT_THROW(b.on_marker(end_run), InputError);  // contradicts the first
}

// Without a key anyone may send an END_RUN. One the run's own messages contradict -- a
// second END_RUN stating another number, an episode at or past its number (sent before it,
// or after, also once the data set has been taken), a number below an episode already
// begun -- marks the run contradicted (the optimiser then fails it, loudly): before, an
// END_RUN of 2 sent after the first episode ended made the data set complete with 2 of
// the run's episodes.
TEST(DatasetBuilder, AnEndRunTheRunContradictsFailsIt) {
  const auto marker = [](int episode, std::int8_t kind, int num_steps) {
    hbirl::episode_marker_t m{};
    m.domain = "gridworld";
    m.episode = episode;
    m.kind = kind;
    m.num_steps = num_steps;
    m.frames_per_step = 1;
    return m;
  };
  const auto frame = [](int episode) { return one_observation(2, {1.0}, episode); };
  const auto episode = [&](DatasetBuilder& b, int e) {
    b.on_marker(marker(e, hbirl::episode_marker_t::BEGIN_EPISODE, 0));
    b.on_observations(frame(e));
    b.on_marker(marker(e, hbirl::episode_marker_t::END_EPISODE, 1));
  };
  using M = hbirl::episode_marker_t;
  {  // the report's attack: END_RUN of 2 after the first episode; the sensor goes on to episode 2
    DatasetBuilder b;
    episode(b, 0);
    b.on_marker(marker(0, M::END_RUN, 2));
    EXPECT_TRUE(b.contradiction().empty());
    episode(b, 1);
    EXPECT_TRUE(b.complete());  // what a forger wants: 2 of the run's episodes make a data set
    b.on_marker(marker(2, M::BEGIN_EPISODE, 0));
    EXPECT_NE(b.contradiction().find("episode 2 after END_RUN said the run had 2"), std::string::npos)
        << b.contradiction();
  }
  {  // the same, the sensor's next episode only heard once the data set was taken
    DatasetBuilder b;
    episode(b, 0);
    b.on_marker(marker(0, M::END_RUN, 2));
    episode(b, 1);
    ASSERT_TRUE(b.complete());
    EXPECT_EQ(b.take().observed.size(), 2u);
    b.on_observations(frame(2));
    EXPECT_FALSE(b.contradiction().empty());
  }
  {  // the sensor's own END_RUN, stating the run's 3 episodes, after the forged one
    DatasetBuilder b;
    episode(b, 0);
    b.on_marker(marker(0, M::END_RUN, 1));
    b.take();
    EXPECT_THROW(b.on_marker(marker(0, M::END_RUN, 3)), InputError);
    EXPECT_NE(b.contradiction().find("END_RUN of 3 episodes after one of 1"), std::string::npos) << b.contradiction();
  }
  {  // a number below an episode already begun
    DatasetBuilder b;
    episode(b, 0);
    b.on_marker(marker(4, M::BEGIN_EPISODE, 0));
    b.on_marker(marker(0, M::END_RUN, 3));
    EXPECT_FALSE(b.contradiction().empty());
  }
  {  // an END_RUN that states no number (a sensor may not know it): a run complete when
     // taken is closed -- an episode it did not have, or an END_RUN stating another number,
     // contradicts it (the reviewer's attack: 3 of 20 demonstrations, exit 0)
    DatasetBuilder b;
    episode(b, 0);
    episode(b, 1);
    b.on_marker(marker(0, M::END_RUN, 0));
    ASSERT_TRUE(b.complete());
    EXPECT_EQ(b.take().observed.size(), 2u);
    b.on_marker(marker(0, M::END_RUN, 0));
    b.on_marker(marker(1, M::END_EPISODE, 1));
    EXPECT_TRUE(b.contradiction().empty()) << b.contradiction();
    b.on_marker(marker(2, M::BEGIN_EPISODE, 0));
    EXPECT_NE(b.contradiction().find("episode 2"), std::string::npos) << b.contradiction();
    DatasetBuilder c;
    episode(c, 0);
    c.on_marker(marker(0, M::END_RUN, 0));
    c.take();
    // ... and is believed only with a run key: on a bus anyone may publish to, a forger
    // could end the run with one in any pause of the sensor's (second review).
    auto hub = std::make_shared<MemoryHub>();
    MemoryBus open_bus(hub);
    Counters unauthenticated = testing::quiet("optimiser");
    DatasetBuilder d;
    d.subscribe(open_bus, unauthenticated);
    episode(d, 0);
    EXPECT_THROW(d.on_marker(marker(0, M::END_RUN, 0)), InputError);
    EXPECT_FALSE(d.run_ended());
    unauthenticated.authenticated = true;
    d.on_marker(marker(0, M::END_RUN, 0));
    EXPECT_TRUE(d.complete());
    EXPECT_THROW(c.on_marker(marker(0, M::END_RUN, 10)), InputError);
    EXPECT_NE(c.contradiction().find("END_RUN of 10 episodes after one of 1"), std::string::npos) << c.contradiction();
  }
  {  // the sensor's END_RUN, repeated: nothing contradicts it
    DatasetBuilder b;
    for (int e = 0; e < 3; ++e) episode(b, e);
    for (int k = 0; k < 3; ++k) b.on_marker(marker(0, M::END_RUN, 3));
    ASSERT_TRUE(b.complete());
    b.take();
    for (int e = 0; e < 3; ++e) b.on_marker(marker(e, M::END_EPISODE, 1));
    b.on_marker(marker(0, M::END_RUN, 3));
    EXPECT_TRUE(b.contradiction().empty()) << b.contradiction();
    EXPECT_EQ(b.end_runs_heard(), 4);
  }
}

// take() hands over the data set that build() assembles, letting each episode's frames
// go as it is assembled (so the optimiser never holds the observations twice), and
// leaves the builder empty.
TEST(DatasetBuilder, TakeGivesWhatBuildGives) {
  DatasetBuilder b;
  hbirl::episode_marker_t marker{};
  marker.domain = "gridworld";
  marker.num_steps = 3;
  marker.frames_per_step = 2;
  for (int episode = 0; episode < 4; ++episode) {
    marker.episode = episode;
    marker.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
    marker.controlled = episode == 0;
    b.on_marker(marker);
    for (int step = 0; step < 3; ++step) {
      hbirl::ground_truth_t t{};
      t.domain = "gridworld";
      t.episode = episode;
      t.step = step;
      t.state = episode + step;
      t.action = step % 4;
      if (episode != 2 || step != 1) b.on_truth(t);  // episode 2 lost a GROUND_TRUTH
      for (int frame = 0; frame < 2; ++frame) {
        if (episode == 3 && step == 2 && frame == 1) continue;  // and episode 3 a frame
        hbirl::observations_t o{};
        o.episode = episode;
        o.step = step;
        o.frame = frame;
        o.num_symbols = 4;
        o.num_sources = 2;
        o.n = 1 + frame;
        for (int n = 0; n < o.n; ++n) {
          o.symbol.push_back(static_cast<std::int16_t>((episode + step + n) % 4));
          const double p = 0.1 * (1 + (episode + frame + n) % 9);
          o.eta.push_back({p, 1.0 - p});
        }
        b.on_observations(o);
      }
    }
    marker.kind = hbirl::episode_marker_t::END_EPISODE;
    b.on_marker(marker);
  }
  const std::int64_t frames = b.frames();
  const Dataset built = b.build();
  const Dataset taken = b.take();
  ASSERT_EQ(built.observed.size(), 3u);
  ASSERT_EQ(taken.observed.size(), built.observed.size());
  for (size_t i = 0; i < built.observed.size(); ++i) {
    EXPECT_EQ(taken.observed[i].symbols, built.observed[i].symbols);
    EXPECT_EQ(taken.observed[i].eta, built.observed[i].eta);
    EXPECT_EQ(taken.observed[i].step_begin, built.observed[i].step_begin);
    EXPECT_EQ(taken.observed[i].contexts, built.observed[i].contexts);
    EXPECT_EQ(taken.observed[i].ends_in_terminal, built.observed[i].ends_in_terminal);
  }
  EXPECT_EQ(taken.skipped_controlled, built.skipped_controlled);
  EXPECT_EQ(taken.contexts_note, built.contexts_note);
  EXPECT_EQ(taken.last_utime, built.last_utime);
  EXPECT_EQ(taken.num_sources, built.num_sources);
  EXPECT_EQ(taken.episodes, built.episodes);
  EXPECT_EQ(taken.truth.size(), built.truth.size());  // none: episode 2's is incomplete
  ASSERT_EQ(taken.controlled_truth.size(), 1u);
  EXPECT_EQ(taken.controlled_truth, built.controlled_truth);
  EXPECT_EQ(taken.controlled_observed[0].symbols, built.controlled_observed[0].symbols);
  EXPECT_EQ(taken.domain, built.domain);
  EXPECT_EQ(b.episodes(), 0);
  EXPECT_EQ(b.frames(), frames);
  EXPECT_TRUE(b.build().observed.empty());
}

// The builder keeps its counts of what is missing as messages come (complete() is asked
// after every message, and a scan of every frame each time made a 5,000-episode log take
// 90 s to read). Against a scan of what the test itself sent, after every message of
// random runs: frames and truth in any order, repeats, frames beyond the stated steps,
// markers that restate the frames per step, episodes past END_RUN's count.
TEST(DatasetBuilder, KeepsCountOfWhatIsMissing) {
  struct Sent {
    bool marked = false, ended = false, controlled = false;
    int steps = 0, per_step = 1;
    std::set<std::pair<int, int>> frames;
    std::set<int> truth;
  };
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Rng rng(seed);
    DatasetBuilder b;
    DatasetBuilder tally;  // the same messages, only counted (RecordingWatch's)
    tally.tally_only();
    std::map<int, Sent> sent;
    bool run_ended = false;
    const int stated = static_cast<int>(1 + rng.uniform_int(6));  // what an END_RUN that says states
    int run_episodes = 0;                                         // 0: no END_RUN has said
    const auto in_run = [&](int id) { return !run_ended || run_episodes == 0 || id < run_episodes; };
    for (int message = 0; message < 300; ++message) {
      const int id = static_cast<int>(rng.uniform_int(8));
      const bool known = sent.count(id) > 0;
      Sent& e = sent[id];
      e.controlled = id % 3 == 0;
      const int kind = static_cast<int>(rng.uniform_int(12));
      if (kind <= 4) {
        hbirl::observations_t o{};
        o.episode = id;
        o.step = static_cast<int>(rng.uniform_int(5));
        o.frame = static_cast<int>(rng.uniform_int(3));
        o.num_symbols = 2;
        o.num_sources = 1;
        o.n = 1;
        o.symbol = {1};
        o.eta = {{1.0}};
        b.on_observations(o);
        tally.on_observations(o);
        e.frames.insert({o.step, o.frame});
      } else if (kind <= 6) {
        hbirl::ground_truth_t t{};
        t.domain = "gridworld";
        t.episode = id;
        t.step = static_cast<int>(rng.uniform_int(5));
        b.on_truth(t);
        tally.on_truth(t);
        e.truth.insert(t.step);
      } else {
        hbirl::episode_marker_t m{};
        m.domain = "gridworld";
        m.episode = id;
        m.controlled = e.controlled;
        m.frames_per_step = static_cast<int>(1 + rng.uniform_int(2));
        const bool any_ended = std::any_of(sent.begin(), sent.end(), [](const auto& x) { return x.second.ended; });
        if (kind == 9) {  // END_RUN, saying how many episodes or not; before any ended it is refused
          m.kind = hbirl::episode_marker_t::END_RUN;
          m.num_steps = rng.uniform_int(2) ? stated : 0;
          if (!known) sent.erase(id);  // END_RUN names no episode
          if (!any_ended) {
            EXPECT_THROW(b.on_marker(m), InputError);
            EXPECT_THROW(tally.on_marker(m), InputError);
          } else {
            b.on_marker(m);
            tally.on_marker(m);
            run_ended = true;
            if (m.num_steps > 0) run_episodes = m.num_steps;
          }
        } else if (kind == 10 && e.marked) {  // a marker that contradicts the episode's kind: refused
          m.kind = hbirl::episode_marker_t::END_EPISODE;
          m.controlled = !e.controlled;
          m.num_steps = 1;
          EXPECT_THROW(b.on_marker(m), InputError);
          EXPECT_THROW(tally.on_marker(m), InputError);
        } else if (kind == 10) {  // frames per step out of range: refused before any reader (messages.hpp)
          m.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
          m.frames_per_step = 0;
          EXPECT_THROW(validate(m), InputError);
          if (!known) sent.erase(id);  // the builder never heard of it
        } else if (kind == 8) {
          m.kind = hbirl::episode_marker_t::END_EPISODE;
          m.num_steps = static_cast<int>(1 + rng.uniform_int(4));
          b.on_marker(m);
          tally.on_marker(m);
          e.marked = e.ended = true;
          e.steps = m.num_steps;
          e.per_step = m.frames_per_step;
        } else {
          m.kind = kind == 7 ? hbirl::episode_marker_t::BEGIN_EPISODE : hbirl::episode_marker_t::BEGIN_STEP;
          b.on_marker(m);
          tally.on_marker(m);
          e.marked = true;
          e.per_step = m.frames_per_step;
        }
      }
      // The scan: what the builder's counts must say.
      std::int64_t missing_frames = 0, missing_truth = 0;
      int unfinished = 0;
      bool all_there = true;
      for (int i = 0; i < run_episodes; ++i) all_there = all_there && sent.count(i);
      for (const auto& [i, x] : sent) {
        if (!in_run(i)) continue;
        if (!x.ended) {
          ++unfinished;
          continue;
        }
        std::int64_t have = 0;
        for (const auto& [step, frame] : x.frames) have += step < x.steps && frame < x.per_step;
        missing_frames += static_cast<std::int64_t>(x.steps) * x.per_step - have;
        for (int step = 0; x.controlled && step < x.steps; ++step) missing_truth += !x.truth.count(step);
      }
      ASSERT_EQ(b.missing_frames(), missing_frames) << "message " << message;
      ASSERT_EQ(b.missing_truth(), missing_truth) << "message " << message;
      ASSERT_EQ(b.unfinished_episodes(), unfinished) << "message " << message;
      ASSERT_EQ(b.complete(), run_ended && all_there && unfinished == 0 && missing_frames == 0 && missing_truth == 0)
          << "message " << message;
      // The demonstrations with every frame (in any order of markers and frames: a frame may
      // come after its episode's end), and how many of the first, in episode order, are.
      int complete_demonstrations = 0, prefix = 0;
      bool prefix_open = true;
      for (const auto& [i, x] : sent) {
        if (!in_run(i)) continue;
        std::int64_t have = 0;
        for (const auto& [step, frame] : x.frames) have += step < x.steps && frame < x.per_step;
        const bool whole = x.ended && have == static_cast<std::int64_t>(x.steps) * x.per_step;
        complete_demonstrations += !x.controlled && whole;
        if (x.marked && x.controlled) continue;
        prefix_open = prefix_open && whole;
        prefix += prefix_open;
      }
      ASSERT_EQ(b.complete_demonstrations(), complete_demonstrations) << "message " << message;
      ASSERT_EQ(b.complete_demonstration_prefix(), prefix) << "message " << message;
      // The tally says the same of the run.
      ASSERT_EQ(tally.frames(), b.frames()) << "message " << message;
      ASSERT_EQ(tally.missing_frames(), b.missing_frames()) << "message " << message;
      ASSERT_EQ(tally.missing_truth(), b.missing_truth()) << "message " << message;
      ASSERT_EQ(tally.unfinished_episodes(), b.unfinished_episodes()) << "message " << message;
      ASSERT_EQ(tally.complete(), b.complete()) << "message " << message;
      ASSERT_EQ(tally.missing_frame_keys(1000), b.missing_frame_keys(1000)) << "message " << message;
      ASSERT_EQ(tally.contradiction(), b.contradiction()) << "message " << message;
    }
  }
}

TEST(DatasetBuilder, TrueWeightsThatDisagreeLeaveTheIleUnknownAndKeepTheSteps) {
  DatasetBuilder b;
  hbirl::episode_marker_t m{};
  m.domain = "gridworld";
  m.episode = 0;
  m.controlled = true;
  m.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
  m.frames_per_step = 1;
  b.on_marker(m);
  hbirl::ground_truth_t t{};
  t.domain = "gridworld";
  t.num_features = 4;
  t.true_weights = {0, 0, 0, 1};
  b.on_truth(t);
  hbirl::observations_t o = one_observation(3, {1.0, 0.0});
  b.on_observations(o);
  t.step = 1;
  t.true_weights = {0, 0, 1, 0};  // another expert?
  b.on_truth(t);
  o.step = 1;
  b.on_observations(o);
  t.domain = "onion";
  EXPECT_THROW(b.on_truth(t), InputError);  // not this run's domain
  t.domain = "gridworld";
  t.true_weights = {0, 0, std::nan(""), 0};
  t.step = 0;
  b.on_truth(t);  // no more weights are looked at once they disagreed
  m.kind = hbirl::episode_marker_t::END_EPISODE;
  m.num_steps = 2;
  b.on_marker(m);
  const Dataset d = b.build();
  EXPECT_FALSE(d.true_weights.has_value());
  ASSERT_EQ(d.controlled_truth.size(), 1u);
  EXPECT_EQ(d.controlled_truth[0].size(), 2u);
  // Weights that are not numbers never reach a reader (validate, messages.hpp).
  t.true_weights = {0, std::numeric_limits<double>::infinity(), 0, 0};
  EXPECT_THROW(validate(t), InputError);
  t.true_weights = {0, 0, 0, 1};
  t.num_features = -1;
  EXPECT_THROW(validate(t), InputError);
}

// Corrupt inputs to the services: counted, and the services keep going.
TEST(Pipeline, ServicesSurviveBadMessages) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus perception_bus(hub), labeller_bus(hub), test_bus(hub);
  Counters pc = quiet("perception"), lc = quiet("labeller"), tc = quiet("test");
  PerceptionService perception(perception_bus, pc);
  LabellerService labeller(labeller_bus, lc, onion_camera());
  int detections = 0;
  subscribe(test_bus, channels::kDetections, tc, [&](const hbirl::detections_t& d, const Message&) {
    detections += d.height == 240;  // perception's, not the bad one this test sends
  });
  hbirl::camera_frame_t f{};
  f.utime = 1;
  f.seq = 1;
  f.width = 320;
  f.height = 240;
  f.encoding = "png";
  f.data = {1, 2, 3, 4};
  f.size = 4;  // not a PNG
  publish(test_bus, channels::kCamera, f, tc);
  f.encoding = "gif";
  publish(test_bus, channels::kCamera, f, tc);
  const char garbage[] = "xxxxxxxxxxxxxxxxxxxxxxxxxx";
  test_bus.publish(channels::kCamera.name, garbage, sizeof garbage);
  test_bus.publish(channels::kDetections.name, garbage, sizeof garbage);
  hbirl::detections_t bad{};
  bad.width = 320;
  bad.height = 100;  // not the camera's shape
  publish(test_bus, channels::kDetections, bad, tc);
  // A 167-byte PNG whose header states 30000 x 30000 in a 320 x 240 message (the fuzzer's
  // finding, tests/fuzz/RESULTS.md): refused before decoding, nothing allocated for it.
  {
    std::ifstream in(
        std::string(HBIRL_SOURCE_DIR) + "/tests/fuzz/corpus/fuzz_png_frame/finding-png-header-30000x30000.png",
        std::ios::binary);
    const std::vector<std::uint8_t> bomb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bomb.size(), 24u);
    f.encoding = "png";
    f.data = bomb;
    f.size = static_cast<std::int32_t>(bomb.size());
    publish(test_bus, channels::kCamera, f, tc);
  }
  // Then a good frame still goes through both.
  cv::Mat frame(240, 320, CV_8UC3, cv::Scalar(200, 200, 196));
  std::vector<unsigned char> png;
  png = hbirl::perception::encode_png(frame);
  f.encoding = "png";
  f.data.assign(png.begin(), png.end());
  f.size = static_cast<std::int32_t>(png.size());
  f.seq = 2;
  publish(test_bus, channels::kCamera, f, tc);
  for (int i = 0; i < 3; ++i) {
    perception_bus.handle(0);
    labeller_bus.handle(0);
    test_bus.handle(0);
  }
  EXPECT_EQ(pc.bad_messages, 4);
  EXPECT_NE(pc.last_problem.find("30000x30000"), std::string::npos) << pc.last_problem;
  EXPECT_EQ(lc.bad_messages, 2);
  EXPECT_EQ(detections, 1);
}

}  // namespace
}  // namespace hbirl::services

namespace hbirl::services {
namespace {

// examples/corridor.json as a live run: its demonstration published by a Simulator
// (hbirl publish's way) into an optimiser that knows the domain. `hostile` runs first on
// an endpoint of its own (it has no key), once the optimiser listens. With `key`, the
// simulator and the optimiser sign and check every message.
std::optional<OptimiserResult> corridor_run(const std::function<void(Bus&)>& hostile, Counters& opt_counters,
                                            const RunKey* key = nullptr,
                                            const std::string& path = std::string(HBIRL_SOURCE_DIR) +
                                                                      "/examples/corridor.json") {
  const std::shared_ptr<const Domain> domain = open_domain(path);
  auto hub = std::make_shared<MemoryHub>();
  const auto endpoint = [&](Counters& counters) -> std::unique_ptr<Bus> {
    auto raw = std::make_unique<MemoryBus>(hub);
    if (!key) return raw;
    return std::make_unique<KeyedBus>(std::move(raw), *key, counters);
  };
  Counters sim_counters = quiet("publish");
  std::unique_ptr<Bus> sim_endpoint = endpoint(sim_counters);
  Bus& sim_bus = *sim_endpoint;
  MemoryBus hostile_bus(hub);
  SimulatorOptions o;
  o.max_frames_per_second = 0;
  Simulator driver(sim_bus, domain->name(), recorded_run(read_problem_file(path)), o, sim_counters);
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    if (hostile) hostile(hostile_bus);
    driver.publish_run(nullptr);
  });
  std::unique_ptr<Bus> opt_endpoint = endpoint(opt_counters);
  Bus& opt_bus = *opt_endpoint;
  OptimiserOptions options;
  options.domain = domain;
  auto result = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
  sim.join();
  return result;
}

// A sensor that does not fit the domain -- symbols outside its alphabet, eta of the wrong
// length, true states it does not have, another domain's markers -- is refused message by
// message, each reported naming the field; the optimiser learns from the rest exactly what
// it learns without them.
TEST(Pipeline, MessagesThatDoNotFitTheDomainAreRefusedOneByOne) {
  Counters clean_counters = quiet("optimiser");
  const auto clean = corridor_run(nullptr, clean_counters);
  ASSERT_TRUE(clean.has_value());
  EXPECT_EQ(clean_counters.bad_messages, 0);
  Counters opt_counters = quiet("optimiser");
  const auto hostile = [](Bus& bus) {
    Counters c = quiet("hostile");
    hbirl::observations_t symbol{};
    symbol.episode = 0;
    symbol.num_symbols = 2;
    symbol.num_sources = 2;
    symbol.n = 1;
    symbol.symbol = {7};  // the corridor has 2 symbols
    symbol.eta = {{0.5, 0.5}};
    publish(bus, channels::kObservations, symbol, c);
    hbirl::observations_t eta = symbol;
    eta.symbol = {1};
    eta.num_sources = 3;  // the corridor has the subject and one element
    eta.eta = {{0.2, 0.3, 0.5}};
    publish(bus, channels::kObservations, eta, c);
    hbirl::observations_t wide = eta;
    wide.num_symbols = 5;
    wide.num_sources = 2;
    wide.eta = {{0.2, 0.8}};
    publish(bus, channels::kObservations, wide, c);
    hbirl::ground_truth_t truth{};
    truth.domain = "corridor";
    truth.state = 9;  // 4 states
    publish(bus, channels::kGroundTruth, truth, c);
    hbirl::episode_marker_t marker{};
    marker.domain = "warehouse";
    marker.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
    marker.frames_per_step = 1;
    publish(bus, channels::kEpisode, marker, c);
  };
  const auto attacked = corridor_run(hostile, opt_counters);
  ASSERT_TRUE(attacked.has_value());
  EXPECT_EQ(opt_counters.bad_messages, 5);
  EXPECT_NE(opt_counters.last_problem.find("episode_marker.domain"), std::string::npos) << opt_counters.last_problem;
  EXPECT_EQ(attacked->learned.digest, clean->learned.digest);
  for (Eigen::Index k = 0; k < clean->learned.theta.size(); ++k)
    EXPECT_EQ(attacked->learned.theta[k], clean->learned.theta[k]);
}

// examples/corridor.json with an end sensor of two symbols on its exit (terminal state 3)
// and 1-3 reports of it per demonstration, as a file in a fresh folder.
std::string corridor_with_end_sensor() {
  std::ifstream in(std::string(HBIRL_SOURCE_DIR) + "/examples/corridor.json");
  nlohmann::json doc = nlohmann::json::parse(in);
  doc["observation_model"]["end_sensor"] = {{"num_symbols", 2}, {"alpha", {{3, 0, 4.0}, {3, 1, 1.5}}}};
  for (size_t i = 0; i < doc["demonstration"].size(); ++i)
    doc["demonstration"][i]["end_symbols"] = std::vector<int>(1 + i % 3, static_cast<int>(i % 2));
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("hbirl_ended_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "corridor.json").string();  // the stem is the domain's name
  std::ofstream(path) << doc.dump();
  return path;
}

// What an end sensor reported goes over the bus with each episode's end marker: the
// optimiser holds every demonstration's reports as the file has them, learns the sensor's
// O_end, and a marker whose reports are not of the domain's end sensor is refused, naming
// the field, while the rest is learned from as without it.
TEST(Pipeline, EndSensorReportsCrossTheBus) {
  const std::string path = corridor_with_end_sensor();
  const Problem problem = read_problem_file(path);
  Counters clean_counters = quiet("optimiser");
  const auto clean = corridor_run(nullptr, clean_counters, nullptr, path);
  ASSERT_TRUE(clean.has_value());
  EXPECT_EQ(clean_counters.bad_messages, 0) << clean_counters.last_problem;
  ASSERT_EQ(clean->data.observed.size(), problem.demonstration.size());
  for (size_t i = 0; i < problem.demonstration.size(); ++i)
    EXPECT_EQ(clean->data.observed[i].end_symbols, problem.demonstration[i].steps->end_symbols) << i;
  const Eigen::MatrixXd& end = clean->learned.end_sensor;
  ASSERT_EQ(end.rows(), 4);
  EXPECT_NEAR(end.row(3).sum(), 1.0, 1e-12);
  const Eigen::MatrixXd prior = dirichlet_mean(problem.observation_model->end_alpha);
  EXPECT_GT(std::abs(end(3, 0) - prior(3, 0)), 1e-3) << "the reports moved O_end";
  Counters opt_counters = quiet("optimiser");
  const auto hostile = [](Bus& bus) {
    Counters c = quiet("hostile");
    hbirl::episode_marker_t m{};
    m.domain = "corridor";
    m.episode = 0;
    m.kind = hbirl::episode_marker_t::END_EPISODE;
    m.num_steps = 3;
    m.frames_per_step = 1;
    m.ends_in_terminal = true;
    m.num_end_symbols = 5;  // the corridor's end sensor has 2
    m.num_end_reports = 1;
    m.end_report = {4};
    publish(bus, channels::kEpisode, m, c);
    m.num_end_symbols = 2;
    m.end_report = {1};
    m.end_state_known = true;
    m.end_state = 1;  // not terminal
    publish(bus, channels::kEpisode, m, c);
  };
  const auto attacked = corridor_run(hostile, opt_counters, nullptr, path);
  ASSERT_TRUE(attacked.has_value());
  EXPECT_EQ(opt_counters.bad_messages, 2) << opt_counters.last_problem;
  EXPECT_EQ(attacked->learned.theta, clean->learned.theta);
  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

// Forgeries from a process without the run's key -- an END_RUN before the run, another
// alphabet, a step's observations sent ahead of the sensor's, a final REWARD, E-step
// answers, hundreds of sampler heartbeats -- change nothing when the run is signed: the
// same data set and theta as the clean signed run, every forgery counted. Without a key
// the checks that need none still hold: the early END_RUN and the other alphabet are
// refused, and the run learns the clean theta.
TEST(Pipeline, ForgeriesChangeNothingWithAKey) {
  const RunKey key = RunKey::generate();
  Counters clean_counters = quiet("optimiser");
  const auto clean = corridor_run(nullptr, clean_counters, &key);
  ASSERT_TRUE(clean.has_value());
  EXPECT_EQ(clean_counters.bad_messages, 0);
  int forged = 0;
  const auto forge = [&forged](bool with_data) {
    return [&forged, with_data](Bus& bus) {
      Counters c = quiet("forger");
      hbirl::episode_marker_t end{};
      end.domain = "corridor";
      end.kind = hbirl::episode_marker_t::END_RUN;
      end.frames_per_step = 1;
      publish(bus, channels::kEpisode, end, c);
      hbirl::observations_t wide{};
      wide.num_symbols = 5;  // the corridor has 2
      wide.num_sources = 2;
      wide.n = 1;
      wide.symbol = {4};
      wide.eta = {{0.5, 0.5}};
      publish(bus, channels::kObservations, wide, c);
      forged = 2;
      if (!with_data) return;
      for (int step = 0; step < 3; ++step) {  // the sensor's own steps of episode 0, made up and sent first
        hbirl::observations_t ahead{};
        ahead.episode = 0;
        ahead.step = step;
        ahead.num_symbols = 2;
        ahead.num_sources = 2;
        ahead.n = 1;
        ahead.symbol = {1};
        ahead.eta = {{1.0, 0.0}};
        publish(bus, channels::kObservations, ahead, c);
        ++forged;
      }
      hbirl::reward_t reward{};  // a well-formed one: only the key can tell
      reward.domain = "corridor";
      reward.final = true;
      reward.num_features = 1;
      reward.theta = {0.0};
      publish(bus, channels::kReward, reward, c);
      for (int k = 0; k < 300; ++k) {
        hbirl::service_status_t beat{};
        beat.service = "sampler";
        beat.id = "sampler-forged-" + std::to_string(k);
        beat.state = "running";
        publish(bus, channels::kStatus, beat, c);
      }
    };
  };
  Counters keyed_counters = quiet("optimiser");
  const auto keyed = corridor_run(forge(true), keyed_counters, &key);
  ASSERT_TRUE(keyed.has_value());
  EXPECT_EQ(keyed->learned.digest, clean->learned.digest);
  for (Eigen::Index k = 0; k < clean->learned.theta.size(); ++k)
    EXPECT_EQ(keyed->learned.theta[k], clean->learned.theta[k]);
  EXPECT_GE(keyed_counters.bad_messages, forged) << "every forgery on the optimiser's channels is counted";
  EXPECT_NE(keyed_counters.last_problem.find("not signed"), std::string::npos) << keyed_counters.last_problem;

  Counters unkeyed_counters = quiet("optimiser");
  const auto unkeyed = corridor_run(forge(false), unkeyed_counters);
  ASSERT_TRUE(unkeyed.has_value());
  EXPECT_EQ(unkeyed_counters.bad_messages, 2);
  EXPECT_EQ(unkeyed->learned.digest, clean->learned.digest);
  for (Eigen::Index k = 0; k < clean->learned.theta.size(); ++k)
    EXPECT_EQ(unkeyed->learned.theta[k], clean->learned.theta[k]);
}

// The simulator as a whole service (Simulator::serve): it starts once the optimiser's
// heartbeat is heard, publishes the run, and returns once the optimiser's reward came.
TEST(Pipeline, SimulatorWaitsForTheOptimiserAndStopsAtItsReward) {
  const std::shared_ptr<const Domain> domain = builtin_domain("gridworld");
  auto hub = std::make_shared<MemoryHub>();
  // Each episode's end is sent once (none was lost, none asked for); END_RUN until the reward.
  std::atomic<int> episode_ends{0}, run_ends{0};
  hub->set_loss([&](const std::string& channel, const std::uint8_t* data, int size) {
    hbirl::episode_marker_t m;
    if (channel == channels::kEpisode.name && m.decode(data, 0, size) > 0) {
      episode_ends += m.kind == hbirl::episode_marker_t::END_EPISODE;
      run_ends += m.kind == hbirl::episode_marker_t::END_RUN;
    }
    return false;
  });
  MemoryBus sim_bus(hub), opt_bus(hub);
  Counters sim_counters = quiet("sim_driver"), opt_counters = quiet("optimiser");
  Simulator driver(sim_bus, *domain, gridworld_run(4, 6, 4), sim_counters);
  std::vector<std::string> said;
  std::atomic<bool> served{false};
  std::thread sim([&] {
    const auto start = std::chrono::steady_clock::now();
    served = driver.serve(nullptr, 30.0, nullptr, [&said](const std::string& s) { said.push_back(s); });
    // It did not sit out its 30 s start delay: it heard the optimiser.
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
  });
  Heartbeat heartbeat(opt_bus, opt_counters, "optimiser", "optimiser-test");
  OptimiserOptions options;
  options.beat = [&heartbeat](const std::string& state) { heartbeat.tick(state); };
  const auto result =
      run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { heartbeat.tick("starting", true); });
  sim.join();
  ASSERT_TRUE(result.has_value());
  EXPECT_TRUE(served);
  ASSERT_FALSE(said.empty());
  EXPECT_EQ(said.front().rfind("run published", 0), 0u) << said.front();  // no "starting without hearing from"
  EXPECT_EQ(result->data.observed.size(), 6u);
  EXPECT_EQ(episode_ends, 6 + 4);  // demonstrations and the controlled run's episodes
  EXPECT_GE(run_ends, 1);
}

// An episode's end marker lost on the way is asked for (FRAME_REQUEST, step and frame -1)
// and sent again: the run completes with the data set of a run that lost nothing -- even
// when every one was lost, so that END_RUN is not believed at first (an optimiser that
// missed the whole run, restarted, is in the same place).
TEST(Pipeline, LostEndMarkersAreAskedFor) {
  const SimulatorOptions run = gridworld_run(7, 8, 4);
  const auto clean = run_serving_requests(std::make_shared<MemoryHub>(), *builtin_domain("gridworld"), run, 200);
  ASSERT_TRUE(clean.has_value());
  auto hub = std::make_shared<MemoryHub>();
  std::set<int> lost;  // the first END_EPISODE of every episode
  hub->set_loss([&lost](const std::string& channel, const std::uint8_t* data, int size) {
    hbirl::episode_marker_t m;
    return channel == channels::kEpisode.name && m.decode(data, 0, size) > 0 &&
           m.kind == hbirl::episode_marker_t::END_EPISODE && lost.insert(m.episode).second;
  });
  std::int64_t resent = 0;
  const auto live = run_serving_requests(hub, *builtin_domain("gridworld"), run, 200, &resent);
  ASSERT_TRUE(live.has_value());
  EXPECT_EQ(lost.size(), 12u);
  EXPECT_GE(resent, 12);
  EXPECT_GT(live->frame_requests, 0);
  EXPECT_TRUE(live->incomplete.empty()) << live->incomplete;
  EXPECT_EQ(dataset_digest(live->data.observed), dataset_digest(clean->data.observed));
  EXPECT_EQ(dataset_digest(live->data.controlled_observed), dataset_digest(clean->data.controlled_observed));
}

}  // namespace
}  // namespace hbirl::services
