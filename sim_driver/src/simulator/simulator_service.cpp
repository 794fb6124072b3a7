// The simulator service (simulator_service.hpp): the domain plans the run up front -- its
// episodes, the expert's steps and what any frame of it shows -- so a frame can be
// published again, identical, whenever it is asked for.
#include <chrono>
#include <cmath>
#include <set>
#include <thread>

#include "learner/input_error.hpp"
#include "sim_driver/simulator/simulator_service.hpp"
#include "perception/image_codec.hpp"

#include "services/lcm_arrays.hpp"

#include "hbirl/reward_t.hpp"
#include "hbirl/service_status_t.hpp"
#include "hbirl/stop_t.hpp"

namespace hbirl {

namespace channels = services::channels;
using services::Bus;
using services::Counters;
using services::lcm_rows;
using services::lcm_vector;
using services::Message;
using services::publish;
using services::subscribe;
using services::Subscriptions;

namespace {

using Clock = std::chrono::steady_clock;

std::int64_t micros(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e6)); }

}  // namespace

namespace {

// A sensor's frames carry every observation of their step.
hbirl::observations_t step_observations(const ObservedTrajectory& tr, int t, int num_symbols, int num_sources) {
  hbirl::observations_t m{};
  m.step = t;
  m.num_symbols = num_symbols;
  m.num_sources = num_sources;
  const int begin = tr.step_begin[static_cast<size_t>(t)], end = tr.step_begin[static_cast<size_t>(t) + 1];
  for (int n = begin; n < end; ++n) m.symbol.push_back(static_cast<std::int16_t>(tr.symbols[static_cast<size_t>(n)]));
  m.eta = lcm_rows(tr.eta.middleRows(begin, end - begin));
  m.n = static_cast<std::int32_t>(m.symbol.size());
  if (!tr.contexts.empty()) {  // the sensor's contexts (a problem file's [symbol, eta, context])
    m.context.assign(tr.contexts.begin() + begin, tr.contexts.begin() + end);
    m.num_context = m.n;
  }
  return m;
}

}  // namespace

Simulator::Simulator(Bus& bus, const Domain& domain, const SimulatorOptions& o, Counters& counters)
    : Simulator(bus, domain.name(), domain.simulate(o.simulation), o, counters) {}

Simulator::Simulator(Bus& bus, std::string domain_name, std::unique_ptr<Simulation> run, const SimulatorOptions& o,
                     Counters& counters)
    : bus_(bus), options_(o), counters_(counters), domain_(std::move(domain_name)), run_(std::move(run)) {
  if (o.encoding != "png" && o.encoding != "jpeg") throw InputError("encoding", "must be png or jpeg");
  subs_.add(bus_, subscribe(
                      bus_, channels::kFrameRequest, counters_,
                      [this](const hbirl::frame_request_t& m, const Message&) { on_request(m); }, 100));
  subs_.add(bus_, subscribe(bus_, channels::kReward, counters_, [this](const hbirl::reward_t& r, const Message&) {
              // Another run's optimiser (another domain) does not end this one.
              if (r.domain != domain_) throw InputError("reward.domain", "'" + r.domain + "' is not this run's");
              if (r.final && !reward_) reward_ = Eigen::Map<const Eigen::VectorXd>(r.theta.data(), r.num_features);
            }));
  subs_.add(bus_, subscribe(bus_, channels::kStop, counters_, [this](const hbirl::stop_t& m, const Message&) {
              // Another run's optimiser does not end this one.
              if (m.domain != domain_) throw InputError("stop.domain", "'" + m.domain + "' is not this run's");
              told_to_stop_ = true;
            }));
}

int Simulator::episodes_in_run() const {
  return episodes_in_run_ >= 0 ? episodes_in_run_ : static_cast<int>(run_->episodes.size());
}

Simulator::~Simulator() = default;

std::vector<std::string> Simulator::listeners() const {
  if (run_->camera()) return {"perception", "labeller", "optimiser"};
  return {"optimiser"};
}

void Simulator::publish_frame(int id, int t, int k) {
  const Simulation::Episode& e = run_->episodes[static_cast<size_t>(id)];
  if (!run_->camera()) {
    hbirl::observations_t m = step_observations(run_->observed(id), t, run_->num_symbols, run_->num_sources);
    m.utime = micros(e.start_time + (t + 0.5) * run_->step_seconds);  // observed mid-step
    m.seq = ++frame_seq_;
    m.episode = id;
    m.frame = k;
    publish(bus_, channels::kObservations, m, counters_);
    return;
  }
  const double time = run_->render(id, t, k, frame_);
  bytes_ = options_.encoding == "png" ? perception::encode_png(frame_) : perception::encode_jpeg(frame_);
  hbirl::camera_frame_t f{};
  f.utime = micros(time);
  f.seq = ++frame_seq_;
  f.episode = id;
  f.step = t;
  f.frame = k;
  f.width = static_cast<std::int16_t>(frame_.cols);
  f.height = static_cast<std::int16_t>(frame_.rows);
  f.encoding = options_.encoding;
  f.size = static_cast<std::int32_t>(bytes_.size());
  f.data.assign(bytes_.begin(), bytes_.end());
  publish(bus_, channels::kCamera, f, counters_);
}

hbirl::episode_marker_t Simulator::marker(int episode, std::int8_t kind, double time) {
  hbirl::episode_marker_t m{};
  m.utime = micros(time);
  m.seq = ++marker_seq_;
  m.domain = domain_;
  m.episode = episode;
  m.controlled = kind != hbirl::episode_marker_t::END_RUN && run_->episodes[static_cast<size_t>(episode)].controlled;
  m.kind = kind;
  m.frames_per_step = run_->frames_per_step;
  return m;
}

void Simulator::on_request(const hbirl::frame_request_t& m) {
  const Simulation& p = *run_;
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<size_t>(i);
    const int id = m.episode[k], t = m.step[k], f = m.frame[k];
    if (t == -1 && f == -1) continue;  // an episode's end marker: sent below if it was sent before
    if (id < 0 || id >= static_cast<int>(p.episodes.size()) || t < 0 ||
        t >= static_cast<int>(p.episodes[static_cast<size_t>(id)].steps.size()) || f < 0 || f >= p.frames_per_step) {
      throw InputError("frame_request[" + std::to_string(i) + "]", "is not a frame of this run");
    }
  }
  std::set<std::pair<int, int>> steps;  // their ground truth again too (it may be what was lost)
  for (int i = 0; i < m.n; ++i) {
    const auto k = static_cast<size_t>(i);
    if (m.step[k] == -1) {
      // Only an end that was, and the others skipped, not refused with the request: an
      // optimiser that heard an END_RUN (perhaps a forged one, stating more episodes) may ask
      // for the end of an episode still going on, or of none at all.
      const int id = m.episode[k];
      if (id >= 0 && static_cast<size_t>(id) < ended_.size() && ended_[static_cast<size_t>(id)]) {
        publish_end(m.episode[k]);
        ++resent_;
      }
      continue;
    }
    if (steps.emplace(m.episode[k], m.step[k]).second) publish_truth(m.episode[k], m.step[k]);
    publish_frame(m.episode[k], m.step[k], m.frame[k]);
    ++resent_;
  }
}

void Simulator::publish_truth(int id, int t) {
  const Simulation& p = *run_;
  const Simulation::Episode& e = p.episodes[static_cast<size_t>(id)];
  if (!e.has_truth) return;
  hbirl::ground_truth_t truth{};
  truth.utime = micros(e.start_time + t * p.step_seconds);
  truth.seq = ++truth_seq_;
  truth.domain = domain_;
  truth.episode = id;
  truth.step = t;
  truth.state = e.steps[static_cast<size_t>(t)].state;
  truth.action = e.steps[static_cast<size_t>(t)].action;
  truth.num_features = static_cast<std::int32_t>(p.true_weights.size());
  truth.true_weights = lcm_vector(p.true_weights);
  publish(bus_, channels::kGroundTruth, truth, counters_);
}

bool Simulator::publish_run(const std::function<bool()>& stop, const std::function<void()>& idle) {
  const Simulation& p = *run_;
  const auto started = Clock::now();
  std::int64_t frames_sent = 0;
  for (int id = 0; id < static_cast<int>(p.episodes.size()); ++id) {
    if (told_to_stop_) {  // seen enough (STOP): the run ends here, complete
      episodes_in_run_ = id;
      break;
    }
    const Simulation::Episode& e = p.episodes[static_cast<size_t>(id)];
    publish_begin(id);
    for (int t = 0; t < static_cast<int>(e.steps.size()); ++t) {
      publish_step_begin(id, t);
      for (int k = 0; k < p.frames_per_step; ++k) {
        if (stop && stop()) return false;
        publish_frame(id, t, k);
        ++frames_sent;
        if (idle) idle();
        if (options_.max_frames_per_second > 0) {
          const auto due = started + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                                         static_cast<double>(frames_sent) / options_.max_frames_per_second));
          std::this_thread::sleep_until(due);
        }
      }
    }
    publish_end(id);
    if (idle) idle();  // a STOP heard now ends the run before the next episode
  }
  publish_end_of_run();
  return true;
}

void Simulator::publish_begin(int id) {
  const Simulation::Episode& e = run_->episodes[static_cast<size_t>(id)];
  publish(bus_, channels::kEpisode, marker(id, hbirl::episode_marker_t::BEGIN_EPISODE, e.start_time), counters_);
}

void Simulator::publish_step_begin(int id, int t) {
  const Simulation::Episode& e = run_->episodes[static_cast<size_t>(id)];
  auto m = marker(id, hbirl::episode_marker_t::BEGIN_STEP, e.start_time + t * run_->step_seconds);
  m.step = t;
  publish(bus_, channels::kEpisode, m, counters_);
  publish_truth(id, t);
}

void Simulator::publish_end(int id) {
  ended_.resize(std::max(ended_.size(), static_cast<size_t>(id) + 1), false);
  ended_[static_cast<size_t>(id)] = true;
  publish(bus_, channels::kEpisode, end_marker(id), counters_);
}

void Simulator::publish_end_of_run() { publish(bus_, channels::kEpisode, end_of_run(), counters_); }

hbirl::episode_marker_t Simulator::end_marker(int id) {
  const Simulation::Episode& e = run_->episodes[static_cast<size_t>(id)];
  auto m = marker(id, hbirl::episode_marker_t::END_EPISODE,
                  e.start_time + static_cast<double>(e.steps.size()) * run_->step_seconds);
  m.num_steps = static_cast<std::int32_t>(e.steps.size());
  m.ends_in_terminal = e.ends_in_terminal;
  if (!run_->camera() && e.ends_in_terminal) {  // what was seen of how it ended
    const ObservedTrajectory& seen = run_->observed(id);
    m.end_state_known = seen.end_state >= 0;
    m.end_state = std::max(seen.end_state, 0);
    m.num_end_symbols = run_->num_end_symbols;
    m.num_end_reports = static_cast<std::int32_t>(seen.end_symbols.size());
    for (int w : seen.end_symbols) m.end_report.push_back(static_cast<std::int16_t>(w));
  }
  return m;
}

void Simulator::republish_end_of_run() { publish(bus_, channels::kEpisode, end_of_run(), counters_); }

hbirl::episode_marker_t Simulator::end_of_run() {
  auto m = marker(0, hbirl::episode_marker_t::END_RUN, 0.0);
  m.num_steps = static_cast<std::int32_t>(episodes_in_run());  // END_RUN states the run's episodes
  return m;
}

std::vector<std::string> Simulator::wait_for_listeners(const std::function<bool()>& stop, double seconds,
                                                       const std::function<void(const std::string&)>& beat) {
  // The services downstream listen once their first heartbeat is heard.
  std::set<std::string> waiting;
  for (const auto& l : listeners()) waiting.insert(l);
  Subscriptions subs;
  subs.add(bus_, subscribe(
                     bus_, channels::kStatus, counters_,
                     [&waiting](const hbirl::service_status_t& m, const Message&) { waiting.erase(m.service); }, 1000));
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  while (!waiting.empty() && Clock::now() < until && !(stop && stop())) {
    bus_.handle(50);
    if (beat) beat("starting");
  }
  return {waiting.begin(), waiting.end()};
}

void Simulator::serve_until_learned(const std::function<bool()>& stop,
                                    const std::function<void(const std::string&)>& beat) {
  auto next_markers = Clock::now() + std::chrono::seconds(1);
  while (!reward_ && !(stop && stop())) {
    bus_.handle(100);
    if (beat) beat("serving lost frames");
    if (Clock::now() >= next_markers) {
      republish_end_of_run();
      next_markers = Clock::now() + std::chrono::seconds(1);
    }
  }
}

bool Simulator::serve(const std::function<bool()>& stop, double start_delay_s,
                      const std::function<void(const std::string&)>& beat,
                      const std::function<void(const std::string&)>& log) {
  const auto say = [&log](const std::string& s) {
    if (log) log(s);
  };
  const auto tick = [&beat](const std::string& state) {
    if (beat) beat(state);
  };
  if (const auto unheard = wait_for_listeners(stop, start_delay_s, beat); !unheard.empty()) {
    std::string names;
    for (const auto& w : unheard) names += " " + w;
    say("starting without hearing from:" + names);
  }
  const bool finished = publish_run(stop, [&] {
    bus_.handle(0);
    tick("running");
  });
  say(std::string(finished ? "run published" : "stopped") + "; " + std::to_string(counters_.messages_out) +
      " messages published" +
      (episodes_in_run_ >= 0 ? "; ended after " + std::to_string(episodes_in_run_) + " episodes, as STOP asked" : ""));
  // Then what was lost on the way is sent again when asked for, and END_RUN repeated in
  // case it was lost, until the optimiser has published its reward.
  if (finished) serve_until_learned(stop, beat);
  return finished;
}

bool run_simulator(Bus& bus, const Domain& domain, const SimulatorOptions& o, Counters& counters,
                   const std::function<bool()>& stop, const std::function<void()>& idle) {
  Simulator driver(bus, domain, o, counters);
  return driver.publish_run(stop, idle);
}

}  // namespace hbirl
