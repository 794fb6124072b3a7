// The simulator service (pipeline.hpp): a run is planned up front -- its episodes, the
// expert's steps and how any frame of it is published -- so a frame can be published
// again, identical, whenever it is asked for.
#include <chrono>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <thread>

#include "learner/input_error.hpp"
#include "services/pipeline.hpp"
#include "sim_driver/onion.hpp"
#include "sim_driver/onion_scene.hpp"

namespace hbirl::services {

namespace {

using Clock = std::chrono::steady_clock;

std::int64_t micros(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e6)); }

}  // namespace

struct SimDriver::Plan {
  struct Episode {
    bool controlled = false;
    double start_time = 0.0;  // sim seconds
    Trajectory steps;
    bool ends_in_terminal = false;
  };
  std::string domain;
  std::vector<Episode> episodes;  // the controlled run, then the demonstrations
  int frames_per_step = 1;
  double step_seconds = 1.0;
  Eigen::VectorXd true_weights;
  std::vector<std::string> listeners;
  // Publishes frame k of step t of episode `id`.
  std::function<void(int id, int t, int k)> publish_frame;
};

namespace {

// The onion-sorting run: sorts planned as hbirl experiment onion plans them, rendered by
// the scene's camera frame by frame and published as PNG (or JPEG) on CAMERA.
std::unique_ptr<SimDriver::Plan> onion_plan(Bus& bus, const SimDriverOptions& o, Counters& counters) {
  if (o.encoding != "png" && o.encoding != "jpeg") throw InputError("encoding", "must be png or jpeg");
  struct Camera {
    std::vector<onion::Episode> episodes;
    int controlled = 0;
    std::unique_ptr<onion::OnionScene> controlled_camera, camera;
    cv::Mat frame;
    std::vector<unsigned char> bytes;
    std::int64_t seq = 0;
  };
  auto cam = std::make_shared<Camera>();
  const Mdp mdp = onion::make_onion_mdp();
  onion::SceneConfig controlled_scene = onion::SceneConfig::controlled();
  controlled_scene.width = o.scene.width;
  controlled_scene.fps = o.scene.fps;
  controlled_scene.step_seconds = o.scene.step_seconds;
  onion::DemonstrationOptions controlled_sorts;
  controlled_sorts.sorts = o.controlled_sorts;
  cam->episodes = onion::plan_sorts(mdp, controlled_scene, controlled_sorts, o.seed + 1);
  cam->controlled = static_cast<int>(cam->episodes.size());
  double end = 0.0;
  for (const auto& e : cam->episodes) end += static_cast<double>(e.steps.size()) * controlled_scene.step_seconds;
  onion::DemonstrationOptions demo_sorts;
  demo_sorts.sorts = o.sorts;
  demo_sorts.start_time = end;
  for (auto& e : onion::plan_sorts(mdp, o.scene, demo_sorts, o.seed)) cam->episodes.push_back(std::move(e));
  cam->controlled_camera = std::make_unique<onion::OnionScene>(controlled_scene, o.seed + 1);
  cam->camera = std::make_unique<onion::OnionScene>(o.scene, o.seed);

  auto plan = std::make_unique<SimDriver::Plan>();
  plan->domain = "onion";
  plan->frames_per_step = o.scene.frames_per_step();
  plan->step_seconds = o.scene.step_seconds;
  plan->true_weights = onion::expert_weights();
  plan->listeners = {"perception", "labeller", "optimiser"};
  for (int id = 0; id < static_cast<int>(cam->episodes.size()); ++id) {
    const onion::Episode& e = cam->episodes[static_cast<size_t>(id)];
    plan->episodes.push_back({id < cam->controlled, e.start_time, e.steps, true});  // a sort ends with the release
  }
  const std::string encoding = o.encoding;
  plan->publish_frame = [cam, &bus, &counters, encoding](int id, int t, int k) {
    const onion::Episode& e = cam->episodes[static_cast<size_t>(id)];
    const onion::OnionScene& scene = id < cam->controlled ? *cam->controlled_camera : *cam->camera;
    scene.render(e, t, k, cam->frame);
    cv::imencode(encoding == "png" ? ".png" : ".jpg", cam->frame, cam->bytes);
    hbirl::camera_frame_t f{};
    f.utime = micros(scene.time_of(e, t, k));
    f.seq = ++cam->seq;
    f.episode = id;
    f.step = t;
    f.frame = k;
    f.width = static_cast<std::int16_t>(cam->frame.cols);
    f.height = static_cast<std::int16_t>(cam->frame.rows);
    f.encoding = encoding;
    f.size = static_cast<std::int32_t>(cam->bytes.size());
    f.data.assign(cam->bytes.begin(), cam->bytes.end());
    publish(bus, channels::kCamera, f, counters);
  };
  return plan;
}

// The paper's Gridworld (paper §Experiments A): a goal corner and the soft expert's trajectories
// drawn from the seed; the controlled run's observations are the subject's alone (eta
// all on the subject), the demonstrations' are drawn equally from the subject and each
// confounding element and labelled with eta as `eta` says. One OBSERVATIONS message
// per step.
std::unique_ptr<SimDriver::Plan> gridworld_plan(Bus& bus, const SimDriverOptions& o, Counters& counters) {
  const GridworldSimOptions& g = o.gridworld;
  if (g.confounders < 0 || g.confounders > 1000) throw InputError("confounders", "must be in [0, 1000]");
  if (g.per_step < 0 || g.per_step > 100000) throw InputError("per_step", "must be in [0, 100000]");
  if (g.trajectories < 1 || g.controlled_trajectories < 1) throw InputError("trajectories", "must be at least 1");
  if (g.length < 1) throw InputError("length", "must be at least 1");
  if (g.eta == EtaKind::kSubject) throw InputError("eta", "must be uniform or plausible");
  if (!(g.step_seconds > 0.0)) throw InputError("step_seconds", "must be positive");
  struct Sensor {
    std::vector<ObservedTrajectory> observed;  // per episode
    int sources = 1;
    std::int64_t seq = 0;
  };
  auto sensor = std::make_shared<Sensor>();
  sensor->sources = 1 + g.confounders;
  Rng task_rng = Rng(o.seed).split(0);
  const GridworldTask task = make_gridworld_task(GridworldOptions{}, g.trajectories, g.length, task_rng);
  const std::vector<Trajectory> controlled =
      soft_expert_demonstration(task.mdp, task.true_weights, g.controlled_trajectories, g.length, task_rng);
  const Eigen::MatrixXd subject_o = gridworld_subject_observation_model(GridworldOptions{}.size, 1.0);
  Rng obs_rng = task_rng.split(1000 + static_cast<std::uint64_t>(g.confounders));
  const Eigen::MatrixXd confounder_o = random_confounder_observation_model(g.confounders, obs_rng);
  GridworldObservationOptions alone;
  alone.confounders = 0;
  alone.per_step = g.per_step;
  alone.eta = EtaKind::kSubject;
  GridworldObservations run = observe_gridworld(task.mdp, controlled, subject_o, Eigen::MatrixXd(0, 4), alone, obs_rng);
  for (auto& t : run.trajectories) {  // eta (1, 0, ..., 0): the same sources as the demonstrations
    RowMatrix eta = RowMatrix::Zero(t.eta.rows(), sensor->sources);
    eta.col(0).setOnes();
    t.eta = std::move(eta);
  }
  GridworldObservationOptions observe;
  observe.confounders = g.confounders;
  observe.per_step = g.per_step;
  observe.eta = g.eta;
  GridworldObservations demonstrations = observe_gridworld(task.mdp, task.trajectories, subject_o, confounder_o, observe, obs_rng);
  sensor->observed = std::move(run.trajectories);
  for (auto& t : demonstrations.trajectories) sensor->observed.push_back(std::move(t));

  auto plan = std::make_unique<SimDriver::Plan>();
  plan->domain = "gridworld";
  plan->frames_per_step = 1;
  plan->step_seconds = g.step_seconds;
  plan->true_weights = task.true_weights;
  plan->listeners = {"optimiser"};
  double start = 0.0;
  for (size_t i = 0; i < controlled.size() + task.trajectories.size(); ++i) {
    const bool is_controlled = i < controlled.size();
    const Trajectory& steps = is_controlled ? controlled[i] : task.trajectories[i - controlled.size()];
    plan->episodes.push_back({is_controlled, start, steps, false});  // no terminal states: cut off
    start += static_cast<double>(steps.size()) * g.step_seconds;
  }
  SimDriver::Plan* p = plan.get();  // the plan owns the function: it never outlives it
  plan->publish_frame = [sensor, p, &bus, &counters](int id, int t, int) {
    const ObservedTrajectory& tr = sensor->observed[static_cast<size_t>(id)];
    const auto& e = p->episodes[static_cast<size_t>(id)];
    hbirl::observations_t m{};
    m.utime = micros(e.start_time + (t + 0.5) * p->step_seconds);  // observed mid-step
    m.seq = ++sensor->seq;
    m.episode = id;
    m.step = t;
    m.frame = 0;
    m.num_symbols = 4;
    m.num_sources = sensor->sources;
    for (int n = tr.step_begin[static_cast<size_t>(t)]; n < tr.step_begin[static_cast<size_t>(t) + 1]; ++n) {
      m.symbol.push_back(static_cast<std::int16_t>(tr.symbols[static_cast<size_t>(n)]));
      m.eta.emplace_back(tr.eta.row(n).data(), tr.eta.row(n).data() + tr.eta.cols());
    }
    m.n = static_cast<std::int32_t>(m.symbol.size());
    publish(bus, channels::kObservations, m, counters);
  };
  return plan;
}

}  // namespace

SimDriver::SimDriver(Bus& bus, const SimDriverOptions& o, Counters& counters) : bus_(bus), options_(o), counters_(counters) {
  if (o.domain == "onion") {
    plan_ = onion_plan(bus, o, counters);
  } else if (o.domain == "gridworld") {
    plan_ = gridworld_plan(bus, o, counters);
  } else {
    throw InputError("domain", "'" + o.domain + "' is not a simulated domain (onion, gridworld)");
  }
  subs_.add(bus_, subscribe<hbirl::frame_request_t>(bus_, channels::kFrameRequest, counters_,
                                                    [this](const hbirl::frame_request_t& m, const Message&) { on_request(m); }, 100));
}

SimDriver::~SimDriver() = default;

std::vector<std::string> SimDriver::listeners() const { return plan_->listeners; }

hbirl::episode_marker_t SimDriver::marker(int episode, std::int8_t kind, double time) {
  hbirl::episode_marker_t m{};
  m.utime = micros(time);
  m.seq = ++marker_seq_;
  m.domain = plan_->domain;
  m.episode = episode;
  m.controlled = kind != hbirl::episode_marker_t::END_RUN && plan_->episodes[static_cast<size_t>(episode)].controlled;
  m.kind = kind;
  m.frames_per_step = plan_->frames_per_step;
  return m;
}

void SimDriver::on_request(const hbirl::frame_request_t& m) {
  const Plan& p = *plan_;
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<size_t>(i);
    const int id = m.episode[k], t = m.step[k], f = m.frame[k];
    if (id < 0 || id >= static_cast<int>(p.episodes.size()) || t < 0 ||
        t >= static_cast<int>(p.episodes[static_cast<size_t>(id)].steps.size()) || f < 0 || f >= p.frames_per_step) {
      throw InputError("frame_request[" + std::to_string(i) + "]", "is not a frame of this run");
    }
  }
  std::set<std::pair<int, int>> steps;  // their ground truth again too (it may be what was lost)
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<size_t>(i);
    if (steps.emplace(m.episode[k], m.step[k]).second) publish_truth(m.episode[k], m.step[k]);
    p.publish_frame(m.episode[k], m.step[k], m.frame[k]);
    ++resent_;
  }
}

void SimDriver::publish_truth(int id, int t) {
  const Plan& p = *plan_;
  const Plan::Episode& e = p.episodes[static_cast<size_t>(id)];
  hbirl::ground_truth_t truth{};
  truth.utime = micros(e.start_time + t * p.step_seconds);
  truth.seq = ++truth_seq_;
  truth.domain = p.domain;
  truth.episode = id;
  truth.step = t;
  truth.state = e.steps[static_cast<size_t>(t)].state;
  truth.action = e.steps[static_cast<size_t>(t)].action;
  truth.num_features = static_cast<std::int32_t>(p.true_weights.size());
  truth.true_weights.assign(p.true_weights.data(), p.true_weights.data() + p.true_weights.size());
  publish(bus_, channels::kGroundTruth, truth, counters_);
}

bool SimDriver::publish_run(const std::function<bool()>& stop, const std::function<void()>& idle) {
  const Plan& p = *plan_;
  const auto started = Clock::now();
  std::int64_t frames_sent = 0;
  for (int id = 0; id < static_cast<int>(p.episodes.size()); ++id) {
    const Plan::Episode& e = p.episodes[static_cast<size_t>(id)];
    publish(bus_, channels::kEpisode, marker(id, hbirl::episode_marker_t::BEGIN_EPISODE, e.start_time), counters_);
    for (int t = 0; t < static_cast<int>(e.steps.size()); ++t) {
      auto m = marker(id, hbirl::episode_marker_t::BEGIN_STEP, e.start_time + t * p.step_seconds);
      m.step = t;
      publish(bus_, channels::kEpisode, m, counters_);
      publish_truth(id, t);
      for (int k = 0; k < p.frames_per_step; ++k) {
        if (stop && stop()) return false;
        p.publish_frame(id, t, k);
        ++frames_sent;
        if (idle) idle();
        if (options_.max_frames_per_second > 0) {
          const auto due = started + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                                         static_cast<double>(frames_sent) / options_.max_frames_per_second));
          std::this_thread::sleep_until(due);
        }
      }
    }
    publish(bus_, channels::kEpisode, end_marker(id), counters_);
  }
  publish(bus_, channels::kEpisode, marker(0, hbirl::episode_marker_t::END_RUN, 0.0), counters_);
  return true;
}

hbirl::episode_marker_t SimDriver::end_marker(int id) {
  const Plan::Episode& e = plan_->episodes[static_cast<size_t>(id)];
  auto m = marker(id, hbirl::episode_marker_t::END_EPISODE,
                  e.start_time + static_cast<double>(e.steps.size()) * plan_->step_seconds);
  m.num_steps = static_cast<std::int32_t>(e.steps.size());
  m.ends_in_terminal = e.ends_in_terminal;
  return m;
}

void SimDriver::republish_end_markers() {
  for (int id = 0; id < static_cast<int>(plan_->episodes.size()); ++id) publish(bus_, channels::kEpisode, end_marker(id), counters_);
  publish(bus_, channels::kEpisode, marker(0, hbirl::episode_marker_t::END_RUN, 0.0), counters_);
}

bool run_sim_driver(Bus& bus, const SimDriverOptions& o, Counters& counters, const std::function<bool()>& stop,
                    const std::function<void()>& idle) {
  SimDriver driver(bus, o, counters);
  return driver.publish_run(stop, idle);
}

}  // namespace hbirl::services
