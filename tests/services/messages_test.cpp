// One validation per message type (services/messages.hpp): each refuses what it must,
// naming the field, and every reader of the type refuses the same message.
#include <gtest/gtest.h>

#include <limits>
#include <opencv2/core.hpp>
#include <string>

#include "dashboard/state.hpp"
#include "learner/input_error.hpp"
#include "perception/image_codec.hpp"
#include "services/dataset.hpp"
#include "services/labeller_service.hpp"
#include "services/memory_bus.hpp"
#include "services/messages.hpp"
#include "services/perception_service.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl::services {
namespace {

// The field a message's validation names, "" when it passes.
template <class Message>
std::string refused_field(const Message& m) {
  try {
    validate(m);
  } catch (const InputError& e) {
    return e.field();
  }
  return "";
}

hbirl::camera_frame_t good_frame() {
  hbirl::camera_frame_t f{};
  f.width = 32;
  f.height = 24;
  f.encoding = "png";
  const std::vector<std::uint8_t> png = perception::encode_png(cv::Mat(24, 32, CV_8UC3, cv::Scalar(10, 20, 30)));
  f.data.assign(png.begin(), png.end());
  f.size = static_cast<std::int32_t>(f.data.size());
  return f;
}

hbirl::detections_t good_detections() {
  hbirl::detections_t d{};
  d.width = 320;
  d.height = 240;
  d.n = 1;
  d.cls = {hbirl::detections_t::CLASS_ONION};
  d.x = {10.0f};
  d.y = {20.0f};
  d.area = {30};
  d.box_x = {5};
  d.box_y = {15};
  d.box_w = {10};
  d.box_h = {10};
  d.dark_share = {0.5f};
  return d;
}

hbirl::episode_marker_t good_marker(std::int8_t kind) {
  hbirl::episode_marker_t m{};
  m.domain = "gridworld";
  m.kind = kind;
  m.frames_per_step = 1;
  m.num_steps = 3;
  return m;
}

TEST(Messages, CameraFrameRules) {
  EXPECT_EQ(refused_field(good_frame()), "");
  auto f = good_frame();
  f.frame = -1;
  EXPECT_EQ(refused_field(f), "camera_frame.step");
  f = good_frame();
  f.encoding = "gif";
  EXPECT_EQ(refused_field(f), "camera_frame.encoding");
  f = good_frame();
  f.size = f.size + 1;  // more than its data holds
  EXPECT_EQ(refused_field(f), "camera_frame.size");
  f = good_frame();
  f.width = 5000;
  EXPECT_EQ(refused_field(f), "camera_frame.width");
  f = good_frame();
  f.width = 33;  // the image's own header says 32
  EXPECT_EQ(refused_field(f), "camera_frame.width");
  f = good_frame();
  f.data[1] = 'X';  // not a PNG signature
  EXPECT_EQ(refused_field(f), "camera_frame.data");
}

TEST(Messages, DetectionRules) {
  EXPECT_EQ(refused_field(good_detections()), "");
  auto d = good_detections();
  d.cls = {7};
  EXPECT_EQ(refused_field(d), "detections.cls[0]");
  d = good_detections();
  d.x = {320.0f};  // on the frame's edge: outside it
  EXPECT_EQ(refused_field(d), "detections[0]");
  d = good_detections();
  d.dark_share = {std::numeric_limits<float>::quiet_NaN()};
  EXPECT_EQ(refused_field(d), "detections[0]");
  d = good_detections();
  d.height = 0;
  EXPECT_EQ(refused_field(d), "detections.width");
}

TEST(Messages, MarkerAndTruthRules) {
  for (std::int8_t kind : {hbirl::episode_marker_t::BEGIN_EPISODE, hbirl::episode_marker_t::BEGIN_STEP,
                           hbirl::episode_marker_t::END_EPISODE, hbirl::episode_marker_t::END_RUN}) {
    EXPECT_EQ(refused_field(good_marker(kind)), "") << int{kind};
  }
  auto m = good_marker(42);
  EXPECT_EQ(refused_field(m), "episode_marker.kind");
  m = good_marker(hbirl::episode_marker_t::BEGIN_STEP);
  m.step = -1;
  EXPECT_EQ(refused_field(m), "episode_marker.step");
  m = good_marker(hbirl::episode_marker_t::BEGIN_EPISODE);
  m.frames_per_step = kMaxFramesPerStep + 1;
  EXPECT_EQ(refused_field(m), "episode_marker.frames_per_step");
  m = good_marker(hbirl::episode_marker_t::END_EPISODE);
  m.num_steps = 0;
  EXPECT_EQ(refused_field(m), "episode_marker.num_steps");
  m = good_marker(hbirl::episode_marker_t::END_RUN);
  m.frames_per_step = 0;  // END_RUN states no frames
  EXPECT_EQ(refused_field(m), "");
  m.num_steps = -1;
  EXPECT_EQ(refused_field(m), "episode_marker.num_steps");

  // What was seen of the end: only on an END_EPISODE that ended in a terminal state, each
  // report a symbol of the end sensor's alphabet.
  m = good_marker(hbirl::episode_marker_t::END_EPISODE);
  m.ends_in_terminal = true;
  m.end_state_known = true;
  m.end_state = 2;
  m.num_end_symbols = 3;
  m.num_end_reports = 2;
  m.end_report = {0, 2};
  EXPECT_EQ(refused_field(m), "");
  auto cut_off = m;
  cut_off.ends_in_terminal = false;
  EXPECT_EQ(refused_field(cut_off), "episode_marker.end_state_known");
  cut_off.end_state_known = false;
  EXPECT_EQ(refused_field(cut_off), "episode_marker.num_end_reports");
  auto begin = m;
  begin.kind = hbirl::episode_marker_t::BEGIN_EPISODE;
  EXPECT_EQ(refused_field(begin), "episode_marker.end_state_known");
  auto negative = m;
  negative.end_state = -4;
  EXPECT_EQ(refused_field(negative), "episode_marker.end_state");
  auto outside = m;
  outside.end_report = {0, 3};
  EXPECT_EQ(refused_field(outside), "episode_marker.end_report[1]");
  auto alphabet = m;
  alphabet.num_end_symbols = kMaxEndSymbols + 1;
  EXPECT_EQ(refused_field(alphabet), "episode_marker.num_end_symbols");

  hbirl::ground_truth_t t{};
  t.num_features = 2;
  t.true_weights = {1.0, -1.0};
  EXPECT_EQ(refused_field(t), "");
  t.action = -1;
  EXPECT_EQ(refused_field(t), "ground_truth.step");
  t.action = 0;
  t.true_weights[1] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(refused_field(t), "ground_truth.true_weights");
}

// A message every reader of its type must refuse is refused by each, counted as bad: the
// dashboard, the labeller and the optimiser's data set apply one rule.
TEST(Messages, EveryReaderRefusesTheSameMessage) {
  auto hub = std::make_shared<MemoryHub>();
  MemoryBus sender(hub), dashboard_bus(hub), labeller_bus(hub), dataset_bus(hub);
  Counters out, dashboard_counters, labeller_counters, dataset_counters;
  for (Counters* c : {&out, &dashboard_counters, &labeller_counters, &dataset_counters}) c->quiet = true;
  dashboard::DashboardState dashboard;
  dashboard.subscribe(dashboard_bus, dashboard_counters);
  LabellerService labeller(labeller_bus, labeller_counters, *builtin_domain("onion")->camera());
  DatasetBuilder dataset;
  Subscriptions subs;
  subs.add(dataset_bus, subscribe(dataset_bus, channels::kEpisode, dataset_counters,
                                  [&](const hbirl::episode_marker_t& m, const Message&) { dataset.on_marker(m); }));
  auto off_frame = good_detections();
  off_frame.y = {-1.0f};
  publish(sender, channels::kDetections, off_frame, out);
  auto endless = good_marker(hbirl::episode_marker_t::END_EPISODE);
  endless.num_steps = kMaxSteps + 1;
  publish(sender, channels::kEpisode, endless, out);
  for (MemoryBus* bus : {&dashboard_bus, &labeller_bus, &dataset_bus}) {
    while (bus->handle(0) > 0) {
    }
  }
  EXPECT_EQ(dashboard_counters.bad_messages, 2);  // it reads both
  EXPECT_EQ(labeller_counters.bad_messages, 1);
  EXPECT_EQ(dataset_counters.bad_messages, 1);
  EXPECT_NE(labeller_counters.last_problem.find("detections[0]"), std::string::npos) << labeller_counters.last_problem;
  EXPECT_NE(dataset_counters.last_problem.find("episode_marker.num_steps"), std::string::npos)
      << dataset_counters.last_problem;
  EXPECT_EQ(dataset.unfinished_episodes(), 0);  // the refused marker began nothing
}

}  // namespace
}  // namespace hbirl::services
