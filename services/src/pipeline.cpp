#include "services/pipeline.hpp"

#include <chrono>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "learner/input_error.hpp"
#include "learner/estep_exact.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"
#include "perception/labeller.hpp"
#include "services/log_bus.hpp"
#include "sim_driver/onion.hpp"
#include "sim_driver/onion_scene.hpp"

namespace hbirl::services {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

// ---- perception ----

PerceptionService::PerceptionService(Bus& bus, Counters& counters) : bus_(bus), counters_(counters) {
  // Frames come at camera rate; a queue of a few seconds' worth rides out a slow moment.
  subs_.add(bus_, subscribe<hbirl::camera_frame_t>(bus_, channels::kCamera, counters_,
                                                   [this](const hbirl::camera_frame_t& m, const Message&) { on_frame(m); }, 2000));
}

void PerceptionService::on_frame(const hbirl::camera_frame_t& m) {
  counters_.gaps += frames_.see(m.seq);
  if (m.encoding != "png" && m.encoding != "jpeg") throw InputError("camera_frame.encoding", "'" + m.encoding + "' (png or jpeg)");
  if (m.size <= 0) throw InputError("camera_frame.data", "is empty");
  if (m.width < 1 || m.height < 1 || m.width > 4096 || m.height > 4096) {
    throw InputError("camera_frame.width", "the frame must be between 1x1 and 4096x4096");  // before decoding it
  }
  const cv::Mat frame = cv::imdecode(cv::Mat(1, m.size, CV_8UC1, const_cast<std::uint8_t*>(m.data.data())), cv::IMREAD_COLOR);
  if (frame.empty()) throw InputError("camera_frame.data", "does not decode as " + m.encoding);
  if (frame.cols != m.width || frame.rows != m.height) {
    throw InputError("camera_frame.width", "the image is " + std::to_string(frame.cols) + "x" + std::to_string(frame.rows) +
                                               ", the message says " + std::to_string(m.width) + "x" + std::to_string(m.height));
  }
  const std::vector<perception::Detection> found = detector_.detect(frame);
  hbirl::detections_t d{};
  d.utime = m.utime;
  d.seq = ++seq_;
  d.episode = m.episode;
  d.step = m.step;
  d.frame = m.frame;
  d.width = m.width;
  d.height = m.height;
  d.n = static_cast<std::int32_t>(found.size());
  for (const auto& x : found) {
    d.cls.push_back(x.cls == perception::BlobClass::kGripper ? hbirl::detections_t::CLASS_GRIPPER : hbirl::detections_t::CLASS_ONION);
    d.x.push_back(static_cast<float>(x.x));
    d.y.push_back(static_cast<float>(x.y));
    d.area.push_back(x.area);
    d.box_x.push_back(static_cast<std::int16_t>(x.box.x));
    d.box_y.push_back(static_cast<std::int16_t>(x.box.y));
    d.box_w.push_back(static_cast<std::int16_t>(x.box.width));
    d.box_h.push_back(static_cast<std::int16_t>(x.box.height));
    d.dark_share.push_back(static_cast<float>(x.dark_share));
  }
  publish(bus_, channels::kDetections, d, counters_);
}

// ---- labeller ----

LabellerService::LabellerService(Bus& bus, Counters& counters, bool uniform_eta)
    : bus_(bus), counters_(counters), uniform_eta_(uniform_eta) {
  subs_.add(bus_, subscribe<hbirl::detections_t>(bus_, channels::kDetections, counters_,
                                                 [this](const hbirl::detections_t& m, const Message&) { on_detections(m); }, 2000));
}

void LabellerService::on_detections(const hbirl::detections_t& m) {
  counters_.gaps += detections_.see(m.seq);
  onion::SceneConfig config;
  config.width = m.width;
  config.validate();
  if (m.height != config.height()) throw InputError("detections.height", "is not 3/4 of the width (the onion camera's shape)");
  std::vector<perception::Detection> found(static_cast<size_t>(m.n));
  for (int i = 0; i < m.n; ++i) {
    auto& d = found[static_cast<size_t>(i)];
    const auto k = static_cast<size_t>(i);
    if (m.cls[k] != hbirl::detections_t::CLASS_GRIPPER && m.cls[k] != hbirl::detections_t::CLASS_ONION) {
      throw InputError("detections.cls[" + std::to_string(i) + "]", "is not a blob class");
    }
    if (!(m.x[k] >= 0.0f && m.x[k] < m.width) || !(m.y[k] >= 0.0f && m.y[k] < m.height) || m.area[k] <= 0 ||
        !(m.dark_share[k] >= 0.0f && m.dark_share[k] <= 1.0f)) {
      throw InputError("detections[" + std::to_string(i) + "]", "position, area or dark share out of range");
    }
    d.cls = m.cls[k] == hbirl::detections_t::CLASS_GRIPPER ? perception::BlobClass::kGripper : perception::BlobClass::kOnion;
    d.x = m.x[k];
    d.y = m.y[k];
    d.area = m.area[k];
    d.box = cv::Rect(m.box_x[k], m.box_y[k], m.box_w[k], m.box_h[k]);
    d.dark_share = m.dark_share[k];
  }
  const std::vector<perception::Observation> obs = perception::label(found, onion::labeller_options(config, uniform_eta_));
  hbirl::observations_t o{};
  o.utime = m.utime;
  o.seq = ++seq_;
  o.episode = m.episode;
  o.step = m.step;
  o.frame = m.frame;
  o.num_symbols = perception::kNumSymbols;
  o.num_sources = perception::kNumSources;
  o.n = static_cast<std::int32_t>(obs.size());
  for (const auto& x : obs) {
    o.symbol.push_back(static_cast<std::int16_t>(x.symbol));
    o.eta.emplace_back(x.eta.begin(), x.eta.end());
  }
  publish(bus_, channels::kObservations, o, counters_);
}

// ---- optimiser ----

namespace {

// For the dashboard: the learned observation model, and the posterior of the newest
// demonstration under it and theta.
void publish_model(Bus& bus, Counters& counters, const Mdp& mdp, const Dataset& data, std::int64_t utime, int iteration,
                   const Eigen::VectorXd& theta, const ObservationPrior& alpha) {
  const ObservationModel model = dirichlet_mean(alpha);
  hbirl::observation_model_t o{};
  o.utime = utime;
  o.domain = data.domain;
  o.iteration = iteration;
  o.num_states = mdp.num_states;
  o.num_actions = mdp.num_actions;
  o.num_pairs = mdp.num_pairs();
  o.num_symbols = model.num_symbols();
  o.num_confounders = model.num_confounders();
  for (int r = 0; r < o.num_pairs; ++r) {
    std::vector<double>& row = o.subject.emplace_back(static_cast<size_t>(o.num_symbols));
    for (int w = 0; w < o.num_symbols; ++w) row[static_cast<size_t>(w)] = model.subject(r, w);
  }
  for (int e = 0; e < o.num_confounders; ++e) {
    std::vector<double>& row = o.confounders.emplace_back(static_cast<size_t>(o.num_symbols));
    for (int w = 0; w < o.num_symbols; ++w) row[static_cast<size_t>(w)] = model.confounders(e, w);
  }
  publish(bus, channels::kObservationModel, o, counters);
  if (data.observed.empty()) return;
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(theta));
  const TrajectoryPosterior post = ExactEngine(mdp).posterior(policy, model, data.observed.back());
  hbirl::posterior_t p{};
  p.utime = utime;
  p.domain = data.domain;
  p.iteration = iteration;
  p.episode = data.episodes.back();
  p.num_steps = static_cast<std::int32_t>(post.marginals.rows());
  p.num_states = mdp.num_states;
  p.num_actions = mdp.num_actions;
  p.num_pairs = mdp.num_pairs();
  for (Eigen::Index t = 0; t < post.marginals.rows(); ++t) {
    p.marginals.emplace_back(post.marginals.row(t).data(), post.marginals.row(t).data() + post.marginals.cols());
  }
  p.log_likelihood = post.log_likelihood;
  publish(bus, channels::kPosterior, p, counters);
}

}  // namespace

std::optional<OptimiserResult> run_optimiser(Bus& bus, const OptimiserOptions& options, Counters& counters,
                                             const std::function<bool()>& stop,
                                             const std::function<void(const std::string&)>& log,
                                             const std::function<void()>& ready) {
  DatasetBuilder builder;
  builder.subscribe(bus, counters);
  if (ready) ready();
  const auto say = [&log](const std::string& s) {
    if (log) log(s);
  };
  std::int64_t frames = -1;
  auto last_frame = Clock::now();
  auto last_request = Clock::now();
  int result_requests = 0;
  bool announced_end = false;
  while (!builder.complete()) {
    if (stop && stop()) return std::nullopt;
    if (options.beat) options.beat("collecting");
    if (bus.handle(100) < 0) break;  // a log at its end
    if (builder.frames() != frames) {
      frames = builder.frames();
      last_frame = Clock::now();
    }
    if (builder.run_ended() && !announced_end) {
      say("end of the run announced; " + std::to_string(builder.frames()) + " frames observed so far");
      announced_end = true;
    }
    // Frames lost on the way: ask for them again (a few hundred per request), once a second.
    if (builder.run_ended() && Clock::now() - last_frame > std::chrono::milliseconds(options.resend_after_ms) &&
        Clock::now() - last_request > std::chrono::milliseconds(options.resend_after_ms)) {
      const auto missing = builder.missing_frame_keys(500);
      if (!missing.empty()) {
        hbirl::frame_request_t r{};
        r.utime = builder.build_utime();
        r.requester = "optimiser";
        r.n = static_cast<std::int32_t>(missing.size());
        for (const auto& [episode, step, frame] : missing) {
          r.episode.push_back(episode);
          r.step.push_back(step);
          r.frame.push_back(frame);
        }
        publish(bus, channels::kFrameRequest, r, counters);
        say("asked for " + std::to_string(missing.size()) + " lost frames again");
        ++result_requests;
      }
      last_request = Clock::now();
    }
    if (builder.run_ended() && Clock::now() - last_frame > std::chrono::milliseconds(options.quiet_ms)) {
      say("no frames for " + std::to_string(options.quiet_ms) + " ms after the end of the run: learning from what came (" +
          std::to_string(builder.missing_frames()) + " frames missing)");
      break;
    }
  }
  if (stop && stop()) return std::nullopt;
  OptimiserResult result;
  result.data = builder.build();
  result.missing_frames = builder.missing_frames();
  result.frame_requests = result_requests;
  const Mdp mdp = domain_mdp(result.data.domain);
  BusExecutorOptions executor_options = options.executor;
  if (!executor_options.stop) executor_options.stop = stop;
  auto executor = std::make_shared<BusBlockExecutor>(bus, result.data.observed, counters, executor_options);
  say("data: " + std::to_string(result.data.controlled_observed.size()) + " controlled episodes, " +
      std::to_string(result.data.observed.size()) + " demonstrations, " + std::to_string(builder.frames()) + " frames");
  if (options.workers > 0) {
    result.workers = executor->wait_for_workers(options.workers, options.wait_workers_ms);
    say(std::to_string(result.workers) + " of " + std::to_string(options.workers) + " sampler workers ready");
  }
  std::optional<Eigen::VectorXd> truth = result.data.true_weights;
  if (truth && truth->size() != mdp.num_features()) {
    say("the ground truth's true weights do not fit the domain's features: no ILE");
    truth.reset();
  }
  const auto start = Clock::now();
  const std::int64_t utime = result.data.last_utime;
  try {
    result.learned = learn_from_dataset(mdp, result.data, options.learning, executor,
                                        [&](int iteration, double ll, const Eigen::VectorXd& theta, const ObservationPrior& alpha) {
                                          if (stop && stop()) throw Stopped();  // also when computing alone
                                          if (options.beat) options.beat("learning");
                                          publish_model(bus, counters, mdp, result.data, utime, iteration, theta, alpha);
                                          hbirl::em_progress_t p{};
                                          p.utime = utime;
                                          p.restart = 0;
                                          p.iteration = iteration;
                                          p.log_likelihood = ll;
                                          p.ile = truth ? inverse_learning_error(mdp, *truth, theta).ile : -1.0;
                                          p.num_features = static_cast<std::int32_t>(theta.size());
                                          p.theta.assign(theta.data(), theta.data() + theta.size());
                                          const auto s = executor->stats();
                                          p.retries = static_cast<std::int32_t>(s.retried_blocks);
                                          p.local_blocks = static_cast<std::int32_t>(s.local_blocks);
                                          p.seconds = std::chrono::duration<double>(Clock::now() - start).count();
                                          publish(bus, channels::kEmProgress, p, counters);
                                        });
  } catch (const Stopped&) {
    say("stopped while learning");
    return std::nullopt;
  }
  result.estep = executor->stats();
  hbirl::reward_t r{};
  r.utime = utime;
  r.domain = result.data.domain;
  r.final = true;
  r.num_features = static_cast<std::int32_t>(result.learned.theta.size());
  r.theta.assign(result.learned.theta.data(), result.learned.theta.data() + result.learned.theta.size());
  r.num_true = truth ? static_cast<std::int32_t>(truth->size()) : 0;
  if (truth) r.true_theta.assign(truth->data(), truth->data() + truth->size());
  const SoftSolution policy = soft_value_iteration(mdp, mdp.features * result.learned.theta);
  r.num_states = mdp.num_states;
  r.num_actions = mdp.num_actions;
  r.policy.assign(static_cast<size_t>(mdp.num_states), std::vector<double>(static_cast<size_t>(mdp.num_actions)));
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) r.policy[static_cast<size_t>(s)][static_cast<size_t>(a)] = policy.policy[mdp.pair(s, a)];
  }
  r.log_likelihood = result.learned.log_likelihood;
  r.ile = result.learned.ile.value_or(-1.0);
  publish(bus, channels::kReward, r, counters);
  return result;
}

OptimiserResult learn_from_log(const std::string& path, const LearningOptions& options, Counters& counters) {
  LogBus bus(path);
  DatasetBuilder builder;
  builder.subscribe(bus, counters);
  // As the live optimiser does: up to the moment the run is complete.
  while (!builder.complete() && bus.handle(0) >= 0) {
  }
  OptimiserResult result;
  result.data = builder.build();
  result.missing_frames = builder.missing_frames();
  const Mdp mdp = domain_mdp(result.data.domain.empty() ? std::string("?") : result.data.domain);
  result.learned = learn_from_dataset(mdp, result.data, options);
  return result;
}

}  // namespace hbirl::services
