#include "services/pipeline.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <future>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "experiments/onion_data.hpp"
#include "services/log_bus.hpp"
#include "services/memory_bus.hpp"
#include "service_threads.hpp"
#include "sim_driver/onion.hpp"

namespace hbirl::services {
namespace {

using testing::quiet;
using testing::ServiceThread;
using testing::WorkerThread;


SimDriverOptions small_run() {
  SimDriverOptions o;
  o.scene.fps = 5;  // 10 frames per step: a short run
  o.controlled_sorts = 6;
  o.sorts = 4;
  o.seed = 3;
  o.max_frames_per_second = 0;
  return o;
}

// The whole onion pipeline in one process, each service on its own endpoint and thread:
// camera frames (PNG) -> perception -> labeller -> optimiser with two sampler workers.
// Everything the live run records also comes back from the log.
TEST(Pipeline, OnionFromFramesToRewardAndFromItsLog) {
  const SimDriverOptions run = small_run();
  const Mdp mdp = onion::make_onion_mdp();
  auto hub = std::make_shared<MemoryHub>();
  const std::filesystem::path log_path =
      std::filesystem::temp_directory_path() / ("hbirl_pipeline_" + std::to_string(::getpid()) + ".lcmlog");
  std::optional<OptimiserResult> live;
  {
    // The recorder: every message, as lcm-logger would write it.
    MemoryBus recorder_bus(hub);
    lcm::LogFile log(log_path.string(), "w");
    ASSERT_TRUE(log.good());
    recorder_bus.subscribe(".*", [&log](const Message& m) {
      lcm::LogEvent e;
      e.timestamp = m.recv_utime;
      e.channel = m.channel;
      e.datalen = m.size;
      e.data = const_cast<std::uint8_t*>(m.data);
      log.writeEvent(&e);
    }, 1 << 20);
    std::atomic<bool> stop_recorder{false};
    std::thread recorder([&] {
      while (!stop_recorder) recorder_bus.handle(20);
    });
    ServiceThread<PerceptionService> perception(hub, "perception");
    ServiceThread<LabellerService> labeller(hub, "labeller");
    WorkerThread w1(hub, mdp, "sampler-1"), w2(hub, mdp, "sampler-2");
    MemoryBus sim_bus(hub);
    Counters sim_counters = quiet("sim_driver");
    std::promise<void> listening;
    std::thread sim([&] {
      listening.get_future().wait();  // the optimiser must hear the run from its first message
      run_sim_driver(sim_bus, run, sim_counters, nullptr);
    });
    MemoryBus opt_bus(hub);
    Counters opt_counters = quiet("optimiser");
    OptimiserOptions options;
    options.workers = 2;
    live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
    sim.join();
    stop_recorder = true;
    recorder.join();
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
  controlled.fps = run.scene.fps;
  onion::DemonstrationOptions controlled_sorts;
  controlled_sorts.sorts = run.controlled_sorts;
  const onion::OnionDemonstration c = onion::demonstrate(mdp, controlled, controlled_sorts, run.seed + 1);
  double end = 0.0;
  for (const auto& t : c.truth) end += static_cast<double>(t.size()) * run.scene.step_seconds;
  onion::DemonstrationOptions demo_sorts;
  demo_sorts.sorts = run.sorts;
  demo_sorts.start_time = end;
  const onion::OnionDemonstration d = onion::demonstrate(mdp, run.scene, demo_sorts, run.seed);
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
  const Learned local = learn_from_dataset(mdp, same, LearningOptions{});
  for (int k = 0; k < 4; ++k) EXPECT_EQ(live->learned.theta[k], local.theta[k]) << k;
  // The recorded log replays to the same data and the same theta.
  Counters replay_counters = quiet("replay");
  const OptimiserResult replay = learn_from_log(log_path.string(), LearningOptions{}, replay_counters);
  EXPECT_EQ(replay.learned.digest, live->learned.digest);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(replay.learned.theta[k], live->learned.theta[k]) << k;
  std::filesystem::remove(log_path);
}

// Camera frames lost on the way (every 6th, and again when sent again): the optimiser asks
// for them (FRAME_REQUEST), the simulator renders them again, and the data set is the
// same as without loss.
TEST(Pipeline, LostFramesAreAskedForAgain) {
  const SimDriverOptions run = small_run();
  const Mdp mdp = onion::make_onion_mdp();
  auto hub = std::make_shared<MemoryHub>();
  hub->set_loss([](const std::string& channel, const std::uint8_t* data, int size) {
    if (channel != channels::kCamera) return false;
    hbirl::camera_frame_t f;
    return f.decode(data, 0, size) > 0 && f.seq % 6 == 0;
  });
  ServiceThread<PerceptionService> perception(hub, "perception");
  ServiceThread<LabellerService> labeller(hub, "labeller");
  MemoryBus sim_bus(hub);
  Counters sim_counters = quiet("sim_driver");
  SimDriver driver(sim_bus, run, sim_counters);
  std::atomic<bool> done{false};
  std::promise<void> listening;
  std::thread sim([&] {
    listening.get_future().wait();
    driver.publish_run(nullptr);
    while (!done) sim_bus.handle(20);  // serving FRAME_REQUEST
  });
  MemoryBus opt_bus(hub);
  Counters opt_counters = quiet("optimiser");
  OptimiserOptions options;
  options.resend_after_ms = 200;
  const auto live = run_optimiser(opt_bus, options, opt_counters, nullptr, nullptr, [&] { listening.set_value(); });
  done = true;
  sim.join();
  ASSERT_TRUE(live.has_value());
  EXPECT_GT(hub->dropped(), 0);
  EXPECT_GT(live->frame_requests, 0);
  EXPECT_GT(driver.frames_resent(), 0);
  EXPECT_EQ(live->missing_frames, 0);
  onion::DemonstrationOptions demo_sorts;
  demo_sorts.sorts = run.sorts;
  demo_sorts.start_time = 0.0;
  onion::SceneConfig controlled = onion::SceneConfig::controlled();
  controlled.fps = run.scene.fps;
  onion::DemonstrationOptions controlled_sorts;
  controlled_sorts.sorts = run.controlled_sorts;
  const onion::OnionDemonstration c = onion::demonstrate(mdp, controlled, controlled_sorts, run.seed + 1);
  for (const auto& t : c.truth) demo_sorts.start_time += static_cast<double>(t.size()) * run.scene.step_seconds;
  EXPECT_EQ(dataset_digest(live->data.observed), dataset_digest(onion::demonstrate(mdp, run.scene, demo_sorts, run.seed).observed));
  EXPECT_EQ(dataset_digest(live->data.controlled_observed), dataset_digest(c.observed))
      << live->data.controlled_observed.size() << " controlled episodes (" << live->data.skipped_controlled << " left out) vs "
      << c.observed.size();
}

// Corrupt inputs to the services: counted, and the services keep going.
TEST(Pipeline, ServicesSurviveBadMessages) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus perception_bus(hub), labeller_bus(hub), test_bus(hub);
  Counters pc = quiet("perception"), lc = quiet("labeller"), tc = quiet("test");
  PerceptionService perception(perception_bus, pc);
  LabellerService labeller(labeller_bus, lc);
  int detections = 0;
  subscribe<hbirl::detections_t>(test_bus, channels::kDetections, tc, [&](const hbirl::detections_t& d, const Message&) {
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
  test_bus.publish(channels::kCamera, garbage, sizeof garbage);
  test_bus.publish(channels::kDetections, garbage, sizeof garbage);
  hbirl::detections_t bad{};
  bad.width = 320;
  bad.height = 100;  // not the camera's shape
  publish(test_bus, channels::kDetections, bad, tc);
  // Then a good frame still goes through both.
  cv::Mat frame(240, 320, CV_8UC3, cv::Scalar(200, 200, 196));
  std::vector<unsigned char> png;
  cv::imencode(".png", frame, png);
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
  EXPECT_EQ(pc.bad_messages, 3);
  EXPECT_EQ(lc.bad_messages, 2);
  EXPECT_EQ(detections, 1);
}

}  // namespace
}  // namespace hbirl::services
