#include "dashboard/state.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <utility>

#include "perception/image_codec.hpp"
#include <opencv2/imgproc.hpp>

#include "expect_refused.hpp"
#include "learner/input_error.hpp"
#include "services/channels.hpp"
#include "services/memory_bus.hpp"
#include "services/messages.hpp"

namespace hbirl::dashboard {
namespace {

TEST(DashboardNames, OfEachDomain) {
  const DomainNames onion = builtin_domain("onion")->names(4);
  EXPECT_EQ(onion.states.size(), 27u);
  EXPECT_EQ(onion.actions.size(), 6u);
  EXPECT_EQ(onion.symbols.size(), 22u);
  EXPECT_EQ(onion.sources.size(), 4u);
  EXPECT_EQ(onion.symbols[21], "dark onion");
  const DomainNames grid = builtin_domain("gridworld")->names(4);
  EXPECT_EQ(grid.states.size(), 25u);
  EXPECT_EQ(grid.sources, (std::vector<std::string>{"subject (expert)", "element 1", "element 2", "element 3"}));
  EXPECT_EQ(builtin_domain("chess"), nullptr);
  EXPECT_EQ(builtin_domain("gridworld:7")->names(1).states.size(), 49u);
}

// A camera frame, its detections and its observations (in that order, as perception and
// the labeller send them) make the annotated frame: each box drawn in the colour of its
// most likely source by eta, and listed in the JSON with that source.
TEST(DashboardState, FrameWithDetectionsColouredByMostLikelySource) {
  DashboardState state;
  cv::Mat image(240, 320, CV_8UC3, cv::Scalar(200, 200, 200));
  std::vector<unsigned char> png;
  png = hbirl::perception::encode_png(image);
  hbirl::camera_frame_t f{};
  f.episode = 3;
  f.step = 2;
  f.frame = 1;
  f.utime = 7'500'000;
  f.width = 320;
  f.height = 240;
  f.encoding = "png";
  f.size = static_cast<std::int32_t>(png.size());
  f.data.assign(png.begin(), png.end());
  state.on_camera(f);
  EXPECT_TRUE(state.frame_png().empty());  // no detections yet
  hbirl::detections_t d{};
  d.episode = 3;
  d.step = 2;
  d.frame = 1;
  d.width = 320;
  d.height = 240;
  d.n = 2;
  d.cls = {hbirl::detections_t::CLASS_GRIPPER, hbirl::detections_t::CLASS_ONION};
  d.x = {50, 200};
  d.y = {60, 150};
  d.area = {400, 100};
  d.box_x = {40, 190};
  d.box_y = {50, 140};
  d.box_w = {20, 20};
  d.box_h = {20, 20};
  d.dark_share = {0, 0.2f};
  state.on_detections(d);
  hbirl::observations_t o{};
  o.episode = 3;
  o.step = 2;
  o.frame = 1;
  o.num_symbols = 22;
  o.num_sources = 4;
  o.n = 2;
  o.symbol = {6, 21};
  o.eta = {{0.7, 0.3, 0, 0}, {0.1, 0.05, 0.25, 0.6}};
  const std::int64_t before = state.version();
  state.on_observations(o);
  EXPECT_GT(state.version(), before);
  const nlohmann::json j = state.json(0);
  ASSERT_FALSE(j["camera"].is_null());
  EXPECT_EQ(j["camera"]["episode"], 3);
  EXPECT_DOUBLE_EQ(j["camera"]["sim_seconds"].get<double>(), 7.5);
  ASSERT_EQ(j["camera"]["detections"].size(), 2u);
  EXPECT_EQ(j["camera"]["detections"][0]["source"], 0);  // 0.7: the subject
  EXPECT_EQ(j["camera"]["detections"][1]["source"], 3);  // 0.6: the foreground person
  EXPECT_EQ(j["camera"]["detections"][1]["class"], "onion");
  EXPECT_EQ(j["observations"]["by_source_symbol"][3][21], 1);
  // The drawn frame: the second box's left edge has the foreground person's colour.
  const std::vector<unsigned char> out = state.frame_png();
  const cv::Mat drawn = hbirl::perception::decode_image(out);
  ASSERT_EQ(drawn.cols, 320);
  const std::string hex = j["source_colours"][3];
  const cv::Vec3b px = drawn.at<cv::Vec3b>(150, 190);
  char got[8];
  std::snprintf(got, sizeof got, "#%02x%02x%02x", px[2], px[1], px[0]);
  EXPECT_EQ(std::string(got), hex);
  EXPECT_EQ(drawn.at<cv::Vec3b>(5, 5), cv::Vec3b(200, 200, 200));  // the rest as sent
}

// The posterior: state marginals are the pair marginals summed over actions; the most
// likely pair per step; the ground truth of that episode next to it.
TEST(DashboardState, PosteriorAgainstGroundTruth) {
  DashboardState state;
  hbirl::posterior_t p{};
  p.domain = "gridworld";
  p.episode = 4;
  p.iteration = 9;
  p.num_steps = 2;
  p.num_states = 25;
  p.num_actions = 4;
  p.num_pairs = 100;
  p.marginals.assign(2, std::vector<double>(100, 0.0));
  p.marginals[0][4 * 7 + 1] = 0.6;  // state 7, action 1
  p.marginals[0][4 * 7 + 2] = 0.1;
  p.marginals[0][4 * 3 + 0] = 0.3;
  p.marginals[1][4 * 8 + 3] = 1.0;
  state.on_posterior(p);
  EXPECT_TRUE(state.json(0)["posterior"]["truth"].is_null());
  for (int t = 0; t < 2; ++t) {
    hbirl::ground_truth_t g{};
    g.domain = "gridworld";
    g.episode = 4;
    g.step = t;
    g.state = t == 0 ? 7 : 9;
    g.action = t == 0 ? 1 : 3;
    g.num_features = 4;
    g.true_weights = {0, 1, 0, 0};
    state.on_truth(g);
  }
  const nlohmann::json j = state.json(0)["posterior"];
  EXPECT_EQ(j["episode"], 4);
  EXPECT_NEAR(j["state_marginals"][0][7].get<double>(), 0.7, 1e-15);
  EXPECT_NEAR(j["state_marginals"][0][3].get<double>(), 0.3, 1e-15);
  EXPECT_NEAR(j["action_marginals"][0][1].get<double>(), 0.6, 1e-15);
  EXPECT_NEAR(j["action_marginals"][0][0].get<double>(), 0.3, 1e-15);
  EXPECT_NEAR(j["action_marginals"][1][3].get<double>(), 1.0, 1e-15);
  EXPECT_EQ(j["most_likely"][0]["state"], 7);
  EXPECT_EQ(j["most_likely"][0]["action"], 1);
  EXPECT_EQ(j["most_likely"][1]["state"], 8);
  EXPECT_EQ(j["truth"][1]["state"], 9);
  EXPECT_EQ(state.json(0)["names"]["states"].size(), 25u);
  // Not a posterior: refused, and the shown one stays.
  p.num_pairs = 99;
  EXPECT_THROW(state.on_posterior(p), InputError);
  p.num_pairs = 100;
  p.marginals[1][0] = 1.5;
  EXPECT_THROW(state.on_posterior(p), InputError);
  EXPECT_EQ(state.json(0)["posterior"]["most_likely"][1]["state"], 8);
}

TEST(DashboardState, LearningProgressThetaAndServices) {
  DashboardState state;
  EXPECT_TRUE(state.json(0)["theta"].is_null());
  for (int it = 1; it <= 3; ++it) {
    hbirl::em_progress_t e{};
    e.iteration = it;
    e.log_likelihood = -100.0 + it;
    e.ile = it == 3 ? 0.0 : -1.0;  // -1: unknown
    e.num_features = 2;
    e.theta = {0.1 * it, -0.1 * it};
    e.retries = it - 1;
    e.prior_strength = it == 3 ? 4.0 : 1.0;  // a new strength: a new objective, the line breaks
    state.on_progress(e);
  }
  hbirl::em_progress_t bad{};
  bad.iteration = 4;
  bad.prior_strength = -1.0;
  EXPECT_THROW(state.on_progress(bad), InputError);
  nlohmann::json j = state.json(0);
  ASSERT_EQ(j["em"].size(), 3u);
  EXPECT_EQ(j["em"][2]["prior_strength"], 4.0);
  EXPECT_TRUE(j["em"][0]["ile"].is_null());
  EXPECT_EQ(j["em"][2]["ile"], 0.0);
  EXPECT_EQ(j["theta"]["learned"][0], 0.1 * 3);
  EXPECT_FALSE(j["theta"]["final"]);
  EXPECT_EQ(j["estep"]["retried_blocks"], 2);
  hbirl::reward_t r{};
  r.domain = "onion";
  r.final = true;
  r.num_features = 2;
  r.theta = {1.0, -1.0};
  r.num_true = 2;
  r.true_theta = {2.0, -2.0};
  r.ile = 0.0;
  // Three states, the last terminal: the policy as results show it, by the domain's names.
  r.num_states = 3;
  r.num_actions = 2;
  r.policy = {{0.25, 0.75}, {0.9, 0.1}, {0.5, 0.5}};
  r.action = {1, 0, -1};
  state.on_reward(r);
  j = state.json(0);
  const nlohmann::json& policy = j["reward"]["policy"];
  EXPECT_EQ(policy["states"], 2);
  ASSERT_EQ(policy["shown"].size(), 2u);
  EXPECT_EQ(policy["shown"][0]["state"], j["names"]["states"].at(0));
  EXPECT_EQ(policy["shown"][0]["action"], j["names"]["actions"].at(1));
  EXPECT_EQ(policy["shown"][0]["probability"], 0.75);
  EXPECT_EQ(policy["shown"][1]["action"], j["names"]["actions"].at(0));
  EXPECT_EQ(policy["shown"][1]["probability"], 0.9);
  services::validate(r);
  // A reward no optimiser sends is refused by its type's validate(), naming the field.
  for (const auto& [field, change] : std::vector<std::pair<std::string, std::function<void(hbirl::reward_t&)>>>{
           {"reward.action", [](hbirl::reward_t& x) { x.action[0] = 2; }},
           {"reward.action", [](hbirl::reward_t& x) { x.action[2] = -2; }},
           {"reward.policy", [](hbirl::reward_t& x) { x.policy[1][0] = 1.5; }},
           {"reward.theta", [](hbirl::reward_t& x) { x.theta[0] = std::nan(""); }},
           {"reward.num_true", [](hbirl::reward_t& x) { x.num_true = 1, x.true_theta = {1.0}; }},
           {"reward.num_features", [](hbirl::reward_t& x) { x.num_features = 0, x.theta.clear(); }},
           {"reward.ile", [](hbirl::reward_t& x) { x.ile = -0.5; }}}) {
    hbirl::reward_t refused = r;
    change(refused);
    try {
      services::validate(refused);
      ADD_FAILURE() << field << ": taken";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), field);
    }
  }
  EXPECT_TRUE(j["theta"]["final"]);
  EXPECT_EQ(j["theta"]["true"][1], -2.0);
  EXPECT_EQ(j["reward"]["ile"], 0.0);
  hbirl::em_progress_t again{};  // a new optimiser run starts over
  again.iteration = 1;
  state.on_progress(again);
  EXPECT_EQ(state.json(0)["em"].size(), 1u);
  hbirl::service_status_t s{};
  s.service = "sampler";
  s.id = "sampler-1";
  s.state = "running";
  s.bad_messages = 5;
  s.restarts = 2;
  s.authenticated = true;
  state.on_status(s, 1'000'000);
  j = state.json(3'500'000);
  ASSERT_EQ(j["services"].size(), 1u);
  EXPECT_DOUBLE_EQ(j["services"][0]["seconds_since_heartbeat"].get<double>(), 2.5);
  EXPECT_EQ(j["services"][0]["bad_messages"], 5);
  EXPECT_EQ(j["services"][0]["restarts"], 2);  // the supervisor's restarts (services/launch.sh)
  EXPECT_EQ(j["services"][0]["authenticated"], true);
  s.id = "";
  EXPECT_THROW(state.on_status(s, 0), InputError);
}

// The optimiser's estimate after each demonstration (ESTIMATE): drawn against the number
// of demonstrations, unknown values as null; a new run starts over; a bad one is refused
// by the type's validate() on the bus (services/messages.hpp), and named.
TEST(DashboardState, EstimatesDemonstrationByDemonstration) {
  DashboardState state;
  EXPECT_TRUE(state.json(0)["estimates"].empty());
  for (int n = 1; n <= 3; ++n) {
    hbirl::estimate_t e{};
    e.domain = "gridworld";
    e.demonstrations = n;
    e.num_features = 1;
    e.theta = {1.0};
    e.confidence = n == 1 ? -1.0 : 0.3 * n;
    e.ile = e.ile_relative = n == 3 ? 0.0 : 0.2;
    e.seconds = 0.1;
    services::validate(e);
    state.on_estimate(e);
  }
  nlohmann::json j = state.json(0);
  ASSERT_EQ(j["estimates"].size(), 3u);
  EXPECT_TRUE(j["estimates"][0]["confidence"].is_null());
  EXPECT_DOUBLE_EQ(j["estimates"][2]["confidence"].get<double>(), 0.3 * 3);
  EXPECT_EQ(j["estimates"][2]["ile_relative"], 0.0);
  hbirl::estimate_t again{};  // a new optimiser run starts over
  again.domain = "gridworld";
  again.demonstrations = 1;
  again.confidence = 0.5;
  state.on_estimate(again);
  EXPECT_EQ(state.json(0)["estimates"].size(), 1u);
  hbirl::estimate_t bad = again;
  bad.num_features = 1;
  bad.theta = {1.0};
  bad.confidence = 1.5;
  try {
    services::validate(bad);
    FAIL() << "a confidence of 1.5 was taken";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "estimate.confidence");
  }
}

// Hostile or stale input: dimensions whose product fools a naive check, frames that are
// never completed (dropped in arrival order, whatever their numbers), text that is not
// UTF-8 (replaced when sent, never a failed page).
// Learned eta per context: the contexts that cover observations, most first, each with
// its stated and learned eta; a model whose eta does not fit its sources, or is not a
// probability, or counts observations negatively is refused naming the field, and the
// page keeps the model it had.
TEST(DashboardState, LearnedEtaPerContext) {
  DashboardState state;
  hbirl::observation_model_t m{};
  m.iteration = 4;
  m.num_states = 1;
  m.num_actions = 1;
  m.num_pairs = 1;
  m.num_symbols = 2;
  m.num_confounders = 1;
  m.subject = {{0.5, 0.5}};
  m.confounders = {{0.2, 0.8}};
  EXPECT_TRUE(state.json(0)["eta"].is_null());
  state.on_model(m);
  EXPECT_TRUE(state.json(0)["eta"].is_null()) << "eta taken as stated: nothing to show";
  m.num_contexts = 3;
  m.num_sources = 2;
  m.stated_eta = {{0.8, 0.2}, {0.5, 0.5}, {0.3, 0.7}};
  m.learned_eta = {{0.4, 0.6}, {0.5, 0.5}, {0.1, 0.9}};
  m.context_observations = {10.0, 0.0, 25.0};
  state.on_model(m);
  const nlohmann::json eta = state.json(0)["eta"];
  EXPECT_EQ(eta["iteration"], 4);
  EXPECT_EQ(eta["with_observations"], 2);
  ASSERT_EQ(eta["contexts"].size(), 2u);
  EXPECT_EQ(eta["contexts"][0]["context"], 2);
  EXPECT_EQ(eta["contexts"][0]["observations"], 25.0);
  EXPECT_EQ(eta["contexts"][1]["context"], 0);
  EXPECT_EQ(eta["contexts"][1]["stated"][0], 0.8);
  EXPECT_EQ(eta["contexts"][1]["learned"][0], 0.4);
  const auto refused = [&state](const hbirl::observation_model_t& bad, const std::string& field) {
    hbirl::testing::expect_refused([&] { state.on_model(bad); }, field);
  };
  hbirl::observation_model_t bad = m;
  bad.num_sources = 3;
  refused(bad, "observation_model.num_sources");
  bad = m;
  bad.learned_eta[1][0] = 1.5;
  refused(bad, "observation_model.learned_eta");
  bad = m;
  bad.stated_eta[0][1] = std::nan("");
  refused(bad, "observation_model.stated_eta");
  bad = m;
  bad.context_observations[2] = -1.0;
  refused(bad, "observation_model.context_observations");
  EXPECT_EQ(state.json(0)["eta"]["contexts"].size(), 2u);
}

TEST(DashboardState, HostileInputCannotBreakThePage) {
  DashboardState state;
  hbirl::posterior_t p{};
  p.num_states = -1;
  p.num_actions = -1;
  p.num_pairs = 1;
  p.num_steps = 0;
  EXPECT_THROW(state.on_posterior(p), InputError);
  hbirl::observation_model_t m{};
  m.num_states = 65536;
  m.num_actions = 65536;  // overflows int
  m.num_pairs = 0;
  m.num_symbols = 1;
  EXPECT_THROW(state.on_model(m), InputError);
  cv::Mat image(240, 320, CV_8UC3, cv::Scalar(10, 20, 30));
  std::vector<unsigned char> png;
  png = hbirl::perception::encode_png(image);
  const auto frame = [&](int episode, int step) {
    hbirl::camera_frame_t f{};
    f.episode = episode;
    f.step = step;
    f.width = 320;
    f.height = 240;
    f.encoding = "png";
    f.size = static_cast<std::int32_t>(png.size());
    f.data.assign(png.begin(), png.end());
    state.on_camera(f);
    hbirl::detections_t d{};
    d.episode = episode;
    d.step = step;
    state.on_detections(d);
  };
  const auto observe = [&](int episode, int step) {
    hbirl::observations_t o{};
    o.episode = episode;
    o.step = step;
    o.num_symbols = 22;
    o.num_sources = 4;
    state.on_observations(o);
  };
  frame(1000000, 0);  // a huge episode number first: it must not stay forever
  for (int t = 0; t < 300; ++t) frame(1, t);
  observe(1000000, 0);
  EXPECT_TRUE(state.json(0)["camera"].is_null());  // dropped: it came first
  observe(1, 299);
  EXPECT_EQ(state.json(0)["camera"]["step"], 299);
  EXPECT_FALSE(state.frame_png().empty());
  hbirl::service_status_t s{};
  s.service = "sampler";
  s.id = "sampler-\xff\xfe";
  s.detail = std::string(5000, 'x') + "\xc3";
  state.on_status(s, 0);
  const nlohmann::json j = state.json(0);
  EXPECT_NO_THROW(j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  EXPECT_LT(j["services"][0]["detail"].get<std::string>().size(), 400u);
}

// Off the bus: garbage and messages that do not validate are counted, and the rest shows.
TEST(DashboardState, BadMessagesOnTheBusAreCounted) {
  auto hub = std::make_shared<services::MemoryHub>();
  services::MemoryBus bus(hub), sender(hub);
  services::Counters counters, out;
  counters.quiet = out.quiet = true;
  DashboardState state;
  state.subscribe(bus, counters);
  const char garbage[] = "garbage garbage garbage";
  for (const std::string* channel :
       {&services::channels::kCamera.name, &services::channels::kPosterior.name, &services::channels::kStatus.name}) {
    sender.publish(*channel, garbage, sizeof garbage);
  }
  hbirl::observation_model_t m{};
  m.domain = "onion";
  m.num_states = 2;
  m.num_actions = 2;
  m.num_pairs = 5;  // not 2 x 2
  services::publish(sender, services::channels::kObservationModel, m, out);
  hbirl::episode_marker_t e{};
  e.domain = "onion";
  e.episode = 2;
  e.kind = hbirl::episode_marker_t::BEGIN_STEP;
  e.step = 4;
  e.frames_per_step = 1;
  services::publish(sender, services::channels::kEpisode, e, out);
  while (bus.handle(0) > 0) {
  }
  EXPECT_EQ(counters.bad_messages, 4);
  const nlohmann::json j = state.json(0);
  EXPECT_EQ(j["domain"], "onion");
  EXPECT_EQ(j["run"]["episode"], 2);
  EXPECT_EQ(j["run"]["step"], 4);
  EXPECT_TRUE(j["model"].is_null());
}

}  // namespace
}  // namespace hbirl::dashboard
