#include "dashboard/state.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "app/output.hpp"
#include "learner/input_error.hpp"
#include "learner/observations.hpp"
#include "perception/image_codec.hpp"
#include "services/channels.hpp"
#include "services/frame_header.hpp"

namespace hbirl::dashboard {

namespace {

constexpr int kMaxSources = 64;
constexpr int kMaxSymbols = 10000;
constexpr int kMaxPairs = 1000000;
constexpr int kMaxSteps = 100000;
constexpr size_t kPendingFrames = 256;  // frames waiting for their detections and observations
constexpr size_t kMaxEpisodes = 10000;  // ground truth kept for the newest episodes
constexpr size_t kMaxIterations = 100000;
constexpr size_t kMaxServices = 1000;
constexpr double kServiceForgotten_s = 600.0;  // a service not heard from for this long is dropped
constexpr size_t kMaxText = 300;

std::string clipped(const std::string& s) { return s.size() > kMaxText ? s.substr(0, kMaxText) + "…" : s; }

// Both dimensions at least 1 and their product num_pairs, without overflow.
bool pairs_fit(int states, int actions, int pairs) {
  return states >= 1 && actions >= 1 && pairs >= 1 && pairs <= kMaxPairs &&
         static_cast<std::int64_t>(states) * actions == static_cast<std::int64_t>(pairs);
}

// One colour per source, the page's and the annotated frame's: subject first.
const std::vector<cv::Scalar>& source_colours() {  // BGR
  static const std::vector<cv::Scalar> c = {{119, 158, 27}, {179, 112, 117}, {2, 95, 217},   {138, 41, 231},
                                            {30, 166, 102}, {2, 171, 230},   {29, 118, 166}, {102, 102, 102}};
  return c;
}

int most_likely(const std::vector<double>& eta) {
  return static_cast<int>(std::max_element(eta.begin(), eta.end()) - eta.begin());
}

template <class Rows>
void check_rows(const Rows& rows, const std::string& field, double lo, double hi) {
  for (const auto& row : rows) {
    for (double x : row) {
      if (!(x >= lo && x <= hi))
        throw InputError(field, "has a value outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
  }
}

nlohmann::json finite_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

// Learned eta for the page: the contexts that cover the most observations (a labeller
// has a few dozen rules; each distinct eta of a sensor without contexts is one), each
// with its stated and learned eta.
constexpr size_t kShownContexts = 24;
nlohmann::json eta_panel_json(const hbirl::observation_model_t& m) {
  std::vector<int> order;
  for (int c = 0; c < m.num_contexts; ++c) {
    if (m.context_observations[static_cast<size_t>(c)] > 0.0) order.push_back(c);
  }
  const size_t shown = std::min(order.size(), kShownContexts);
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(shown), order.end(), [&m](int a, int b) {
    const double na = m.context_observations[static_cast<size_t>(a)],
                 nb = m.context_observations[static_cast<size_t>(b)];
    return na != nb ? na > nb : a < b;
  });
  nlohmann::json contexts = nlohmann::json::array();
  for (size_t k = 0; k < shown; ++k) {
    const auto c = static_cast<size_t>(order[k]);
    contexts.push_back({{"context", order[k]},
                        {"observations", m.context_observations[c]},
                        {"stated", m.stated_eta[c]},
                        {"learned", m.learned_eta[c]}});
  }
  return {{"iteration", m.iteration}, {"contexts", contexts}, {"with_observations", order.size()}};
}

// source_colours() as the page's "#rrggbb".
std::vector<std::string> source_colours_hex() {
  std::vector<std::string> colours;
  for (const auto& c : source_colours()) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "#%02x%02x%02x", static_cast<int>(c[2]), static_cast<int>(c[1]),
                  static_cast<int>(c[0]));
    colours.emplace_back(hex);
  }
  return colours;
}

// The camera's detections, each with its observation: symbol, eta and most likely source.
nlohmann::json detections_json(const hbirl::detections_t& d, const hbirl::observations_t& o, const DomainNames& names) {
  nlohmann::json detections = nlohmann::json::array();
  for (int i = 0; i < d.n && i < o.n; ++i) {
    const auto k = static_cast<size_t>(i);
    const int source = most_likely(o.eta[k]);
    const int symbol = o.symbol[k];
    detections.push_back(
        {{"class", d.cls[k] == hbirl::detections_t::CLASS_GRIPPER ? "gripper" : "onion"},
         {"box", {d.box_x[k], d.box_y[k], d.box_w[k], d.box_h[k]}},
         {"symbol", symbol},
         {"symbol_name",
          symbol < static_cast<int>(names.symbols.size()) ? names.symbols[static_cast<size_t>(symbol)] : ""},
         {"eta", o.eta[k]},
         {"source", source}});
  }
  return detections;
}

// The newest observations (any domain): how many by most likely source, by symbol.
nlohmann::json observation_counts_json(const hbirl::observations_t& o) {
  std::vector<std::vector<int>> counts(static_cast<size_t>(o.num_sources),
                                       std::vector<int>(static_cast<size_t>(o.num_symbols)));
  for (int i = 0; i < o.n; ++i) {
    counts[static_cast<size_t>(most_likely(o.eta[static_cast<size_t>(i)]))]
          [static_cast<size_t>(o.symbol[static_cast<size_t>(i)])]++;
  }
  return {{"episode", o.episode}, {"step", o.step}, {"frame", o.frame}, {"n", o.n}, {"by_source_symbol", counts}};
}

// One entry per EM iteration.
nlohmann::json em_json(const std::vector<hbirl::em_progress_t>& progress) {
  nlohmann::json em = nlohmann::json::array();
  for (const auto& p : progress) {
    em.push_back({{"iteration", p.iteration},
                  {"log_likelihood", finite_or_null(p.log_likelihood)},
                  {"prior_strength", p.prior_strength},
                  {"ile", p.ile >= 0.0 ? finite_or_null(p.ile) : nlohmann::json(nullptr)},
                  {"seconds", p.seconds},
                  {"retries", p.retries},
                  {"local_blocks", p.local_blocks}});
  }
  return em;
}

// One entry per live estimate (a value -1, unknown, as null).
nlohmann::json estimates_json(const std::vector<hbirl::estimate_t>& estimates) {
  const auto known = [](double x) { return x >= 0.0 ? finite_or_null(x) : nlohmann::json(nullptr); };
  nlohmann::json out = nlohmann::json::array();
  for (const auto& e : estimates) {
    out.push_back({{"demonstrations", e.demonstrations},
                   {"confidence", known(e.confidence)},
                   {"ile_relative", known(e.ile_relative)},
                   {"seconds", e.seconds}});
  }
  return out;
}

// The learned reward's policy as every result shows it (app/output.hpp): in each state that
// is not terminal, the action a robot would take and the soft policy's probability of it --
// in the first kPolicyShown such states (the page is polled twice a second; a 200 x 200
// Gridworld's whole policy is in the run's result.json).
constexpr size_t kPolicyShown = 100;
nlohmann::json policy_json(const hbirl::reward_t& reward, const DomainNames& names) {
  std::vector<app::PolicyStep> policy;
  size_t states = 0;
  for (int s = 0; s < reward.num_states && s < static_cast<int>(reward.action.size()); ++s) {
    const int a = reward.action[static_cast<size_t>(s)];
    if (a < 0) continue;
    if (++states <= kPolicyShown)
      policy.push_back({s, a, reward.policy[static_cast<size_t>(s)][static_cast<size_t>(a)]});
  }
  return {{"states", states}, {"shown", app::policy_json<nlohmann::json>(policy, names.states, names.actions)}};
}

// The learned theta (the final reward's, else the newest iteration's) and the true one, or null.
nlohmann::json theta_json(const std::optional<hbirl::reward_t>& reward,
                          const std::vector<hbirl::em_progress_t>& progress,
                          const std::optional<std::vector<double>>& true_weights) {
  nlohmann::json theta = nullptr;
  if (reward) {
    theta = {{"learned", reward->theta}, {"final", reward->final != 0}};
  } else if (!progress.empty()) {
    theta = {{"learned", progress.back().theta}, {"final", false}};
  }
  if (!theta.is_null()) {
    if (true_weights) {
      theta["true"] = *true_weights;
    } else if (reward && reward->num_true > 0) {
      theta["true"] = reward->true_theta;
    } else {
      theta["true"] = nullptr;
    }
  }
  return theta;
}

// The posterior of an episode: per step the state and action marginals, the most likely
// pair and, when every step's ground truth has come, the true pair.
nlohmann::json posterior_json(const hbirl::posterior_t& p,
                              const std::map<int, std::map<int, std::pair<int, int>>>& truth) {
  nlohmann::json marginals = nlohmann::json::array(), action_marginals = nlohmann::json::array();
  nlohmann::json best = nlohmann::json::array();
  for (const auto& row : p.marginals) {
    std::vector<double> states(static_cast<size_t>(p.num_states), 0.0),
        actions(static_cast<size_t>(p.num_actions), 0.0);
    for (int r = 0; r < p.num_pairs; ++r) {
      states[static_cast<size_t>(r / p.num_actions)] += row[static_cast<size_t>(r)];
      actions[static_cast<size_t>(r % p.num_actions)] += row[static_cast<size_t>(r)];
    }
    marginals.push_back(states);
    action_marginals.push_back(actions);
    const int r = static_cast<int>(std::max_element(row.begin(), row.end()) - row.begin());
    best.push_back(
        {{"state", r / p.num_actions}, {"action", r % p.num_actions}, {"probability", row[static_cast<size_t>(r)]}});
  }
  nlohmann::json true_steps = nullptr;
  const auto it = truth.find(p.episode);
  if (it != truth.end() && static_cast<int>(it->second.size()) >= p.num_steps) {
    true_steps = nlohmann::json::array();
    for (int t = 0; t < p.num_steps; ++t) {
      const auto step = it->second.find(t);
      if (step == it->second.end()) {
        true_steps = nullptr;
        break;
      }
      true_steps.push_back({{"state", step->second.first}, {"action", step->second.second}});
    }
  }
  return {{"episode", p.episode},
          {"iteration", p.iteration},
          {"steps", p.num_steps},
          {"state_marginals", marginals},
          {"action_marginals", action_marginals},
          {"most_likely", best},
          {"truth", true_steps},
          {"log_likelihood", finite_or_null(p.log_likelihood)}};
}

// A service's last status and how long ago it was heard (now_utime, heard_utime: wall clock).
nlohmann::json service_json(const std::string& id, const hbirl::service_status_t& m, std::int64_t heard_utime,
                            std::int64_t now_utime) {
  return {{"id", id},
          {"service", m.service},
          {"state", m.state},
          {"seconds_since_heartbeat", std::max<double>(0.0, static_cast<double>(now_utime - heard_utime) * 1e-6)},
          {"messages_in", m.messages_in},
          {"messages_out", m.messages_out},
          {"bad_messages", m.bad_messages},
          {"gaps", m.gaps},
          {"trajectories", m.trajectories},
          {"restarts", m.restarts},
          {"authenticated", m.authenticated != 0},
          {"detail", m.detail}};
}

}  // namespace

void DashboardState::subscribe(services::Bus& bus, services::Counters& counters) {
  using services::Message;
  namespace ch = services::channels;
  // Frames and observations come at camera rate: only the newest matter, but a whole
  // recorded run may be waiting when the dashboard follows a log.
  constexpr int kQueue = 1 << 16;
  subs_.add(bus, services::subscribe(
                     bus, ch::kCamera, counters, [this](const auto& m, const Message&) { on_camera(m); }, kQueue));
  subs_.add(bus,
            services::subscribe(
                bus, ch::kDetections, counters, [this](const auto& m, const Message&) { on_detections(m); }, kQueue));
  subs_.add(bus, services::subscribe(
                     bus, ch::kObservations, counters, [this](const auto& m, const Message&) { on_observations(m); },
                     kQueue));
  subs_.add(bus, services::subscribe(
                     bus, ch::kEpisode, counters, [this](const auto& m, const Message&) { on_marker(m); }, kQueue));
  subs_.add(bus, services::subscribe(
                     bus, ch::kGroundTruth, counters, [this](const auto& m, const Message&) { on_truth(m); }, kQueue));
  subs_.add(bus, services::subscribe(
                     bus, ch::kEmProgress, counters, [this](const auto& m, const Message&) { on_progress(m); }, 10000));
  subs_.add(bus, services::subscribe(
                     bus, ch::kReward, counters, [this](const auto& m, const Message&) { on_reward(m); }, 100));
  subs_.add(bus, services::subscribe(
                     bus, ch::kEstimate, counters, [this](const auto& m, const Message&) { on_estimate(m); }, 1000));
  subs_.add(bus,
            services::subscribe(
                bus, ch::kObservationModel, counters, [this](const auto& m, const Message&) { on_model(m); }, 100));
  subs_.add(bus, services::subscribe(
                     bus, ch::kPosterior, counters, [this](const auto& m, const Message&) { on_posterior(m); }, 100));
  subs_.add(bus, services::subscribe(
                     bus, ch::kStatus, counters,
                     [this](const auto& m, const Message&) { on_status(m, services::wall_utime()); }, 10000));
}

void DashboardState::set_domain(const std::string& domain) {
  if (domain.empty() || domain == domain_) return;
  std::shared_ptr<const Domain> found = given_ && given_->name() == domain ? given_ : builtin_domain(domain);
  if (!found)
    throw InputError("episode_marker.domain",
                     "'" + domain + "' is not a built-in domain: start the dashboard with --domain FILE");
  domain_object_ = std::move(found);
  domain_ = domain;
}

void DashboardState::on_camera(const hbirl::camera_frame_t& m) {
  // frame_png() decodes it: validate(camera_frame_t) has checked that the image's header
  // states the message's size, within perception's limits (services/messages.hpp).
  const std::lock_guard<std::mutex> lock(mutex_);
  Pending& p = pending_[{m.episode, m.step, m.frame}];
  p.image.assign(m.data.begin(), m.data.begin() + m.size);
  p.utime = m.utime;
  p.order = ++pending_order_;
  if (pending_.size() > kPendingFrames) {  // drop the one that came first (not the smallest key)
    auto oldest = pending_.begin();
    for (auto it = pending_.begin(); it != pending_.end(); ++it) {
      if (it->second.order < oldest->second.order) oldest = it;
    }
    pending_.erase(oldest);
  }
  ++frames_;
  sim_utime_ = std::max(sim_utime_, m.utime);
  changed();
}

void DashboardState::on_detections(const hbirl::detections_t& m) {  // validate(detections_t) has checked it
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto it = pending_.find({m.episode, m.step, m.frame});
  if (it != pending_.end()) it->second.detections = m;  // else its frame was never seen (or is long gone)
}

void DashboardState::on_observations(const hbirl::observations_t& m) {
  // validate(observations_t) has checked the message (services/messages.hpp); what the page
  // can draw is bounded here.
  if (m.num_sources > kMaxSources) throw InputError("observations.num_sources", "more than the page shows (64)");
  if (m.num_symbols > kMaxSymbols) throw InputError("observations.num_symbols", "more than the page shows (10000)");
  const std::lock_guard<std::mutex> lock(mutex_);
  num_sources_ = m.num_sources;
  last_observations_ = m;
  const Key key{m.episode, m.step, m.frame};
  const auto it = pending_.find(key);
  if (it != pending_.end() && !it->second.image.empty() && it->second.detections && it->second.detections->n == m.n) {
    frame_ = Frame{key, it->second.utime, std::move(it->second.image), std::move(*it->second.detections), m};
    ++frame_serial_;
    const std::uint64_t shown = it->second.order;
    std::erase_if(pending_,
                  [shown](const auto& entry) { return entry.second.order <= shown; });  // older frames: never shown now
  }
  changed();
}

void DashboardState::on_marker(const hbirl::episode_marker_t& m) {  // validate(episode_marker_t) has checked it
  const std::lock_guard<std::mutex> lock(mutex_);
  set_domain(m.domain);
  switch (m.kind) {
    case hbirl::episode_marker_t::BEGIN_EPISODE:
    case hbirl::episode_marker_t::BEGIN_STEP:
      episode_ = m.episode;
      step_ = m.kind == hbirl::episode_marker_t::BEGIN_STEP ? m.step : 0;
      controlled_ = m.controlled;
      break;
    case hbirl::episode_marker_t::END_EPISODE:
      episodes_ended_ = std::max(episodes_ended_, m.episode + 1);
      break;
    case hbirl::episode_marker_t::END_RUN:
      run_ended_ = true;
      break;
    default:
      throw InputError("episode_marker.kind", std::to_string(m.kind) + " is not a marker kind");
  }
  sim_utime_ = std::max(sim_utime_, m.utime);
  changed();
}

void DashboardState::on_truth(const hbirl::ground_truth_t& m) {
  // validate(ground_truth_t) has checked it (services/messages.hpp); what the page shows is bounded here.
  if (m.num_features > kMaxSymbols) throw InputError("ground_truth.num_features", "more than the page shows (10000)");
  const std::lock_guard<std::mutex> lock(mutex_);
  set_domain(m.domain);
  truth_[m.episode][m.step] = {m.state, m.action};
  while (truth_.size() > kMaxEpisodes) truth_.erase(truth_.begin());
  if (m.num_features > 0) true_weights_ = m.true_weights;
  changed();
}

void DashboardState::on_progress(const hbirl::em_progress_t& m) {
  if (m.iteration < 0) throw InputError("em_progress.iteration", "is negative");
  if (std::isnan(m.log_likelihood)) throw InputError("em_progress.log_likelihood", "is NaN");
  if (!(m.prior_strength >= 0.0) || !std::isfinite(m.prior_strength)) {
    throw InputError("em_progress.prior_strength", "must be finite and at least 0");
  }
  for (double t : m.theta) {
    if (!std::isfinite(t)) throw InputError("em_progress.theta", "must be finite");
  }
  const std::lock_guard<std::mutex> lock(mutex_);
  // A new run of the optimiser starts again from iteration 1.
  if (!progress_.empty() && m.iteration <= progress_.back().iteration) progress_.clear();
  if (progress_.size() >= kMaxIterations)
    throw InputError("em_progress.iteration", "more iterations than the dashboard keeps");
  progress_.push_back(m);
  changed();
}

void DashboardState::on_reward(const hbirl::reward_t& m) {
  for (double t : m.theta) {
    if (!std::isfinite(t)) throw InputError("reward.theta", "must be finite");
  }
  const std::lock_guard<std::mutex> lock(mutex_);
  set_domain(m.domain);
  reward_ = m;
  changed();
}

void DashboardState::on_estimate(const hbirl::estimate_t& m) {
  const std::lock_guard<std::mutex> lock(mutex_);
  set_domain(m.domain);
  // A new run's optimiser starts again from its first demonstration.
  if (!estimates_.empty() && m.demonstrations <= estimates_.back().demonstrations) estimates_.clear();
  if (estimates_.size() >= kMaxIterations) throw InputError("estimate.demonstrations", "more than the dashboard keeps");
  estimates_.push_back(m);
  estimates_.back().policy.clear();  // not shown
  changed();
}

void DashboardState::on_status(const hbirl::service_status_t& m, std::int64_t now_utime) {
  if (m.id.empty()) throw InputError("status.id", "is empty");
  if (m.id.size() > 200 || m.service.size() > 100) throw InputError("status.id", "is too long");
  const std::lock_guard<std::mutex> lock(mutex_);
  std::erase_if(services_, [now_utime](const auto& s) {
    return static_cast<double>(now_utime - s.second.heard_utime) * 1e-6 > kServiceForgotten_s;
  });
  if (services_.size() >= kMaxServices && !services_.count(m.id)) throw InputError("status.id", "too many services");
  Service& s = services_[m.id];
  s.status = m;
  s.status.state = clipped(m.state);
  s.status.detail = clipped(m.detail);
  s.heard_utime = now_utime;
  changed();
}

void DashboardState::on_model(const hbirl::observation_model_t& m) {
  if (!pairs_fit(m.num_states, m.num_actions, m.num_pairs)) {
    throw InputError("observation_model.num_pairs", "must be num_states * num_actions, both at least 1");
  }
  if (m.num_symbols < 1 || m.num_symbols > kMaxSymbols || m.num_confounders < 0 || m.num_confounders > kMaxSources) {
    throw InputError("observation_model.num_symbols", "out of range");
  }
  check_rows(m.subject, "observation_model.subject", 0.0, 1.0);
  check_rows(m.confounders, "observation_model.confounders", 0.0, 1.0);
  if (m.num_contexts < 0 || m.num_contexts > kMaxContexts)
    throw InputError("observation_model.num_contexts", "out of range");
  if (m.num_contexts > 0 && m.num_sources != 1 + m.num_confounders) {
    throw InputError("observation_model.num_sources", "must be 1 + num_confounders");
  }
  check_rows(m.stated_eta, "observation_model.stated_eta", 0.0, 1.0 + 1e-9);
  check_rows(m.learned_eta, "observation_model.learned_eta", 0.0, 1.0 + 1e-9);
  for (double n : m.context_observations) {
    if (!(std::isfinite(n) && n >= 0.0))
      throw InputError("observation_model.context_observations", "must be finite and >= 0");
  }
  const std::lock_guard<std::mutex> lock(mutex_);
  set_domain(m.domain);
  model_ = m;
  changed();
}

void DashboardState::on_posterior(const hbirl::posterior_t& m) {
  if (!pairs_fit(m.num_states, m.num_actions, m.num_pairs)) {
    throw InputError("posterior.num_pairs", "must be num_states * num_actions, both at least 1");
  }
  if (m.num_steps < 0 || m.num_steps > kMaxSteps) throw InputError("posterior.num_steps", "out of range");
  check_rows(m.marginals, "posterior.marginals", 0.0, 1.0 + 1e-9);
  const std::lock_guard<std::mutex> lock(mutex_);
  set_domain(m.domain);
  posterior_ = m;
  changed();
}

std::int64_t DashboardState::version() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

std::vector<unsigned char> DashboardState::frame_png() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!frame_) return {};
  const std::int64_t v = frame_serial_;
  if (v == png_version_) return png_;
  cv::Mat image = perception::decode_image(frame_->image.data(), frame_->image.size());
  if (image.empty()) return {};
  const auto& d = frame_->detections;
  const auto& o = frame_->observations;
  const auto& colours = source_colours();
  for (int i = 0; i < d.n && i < o.n; ++i) {
    const auto k = static_cast<size_t>(i);
    const int source = most_likely(o.eta[k]);
    const cv::Scalar colour = colours[static_cast<size_t>(source) % colours.size()];
    const cv::Rect box(d.box_x[k], d.box_y[k], d.box_w[k], d.box_h[k]);
    cv::rectangle(image, box, colour, 2);
    const std::string label =
        std::to_string(static_cast<int>(std::lround(100 * o.eta[k][static_cast<size_t>(source)]))) + "%";
    cv::putText(image, label, cv::Point(box.x, std::max(10, box.y - 3)), cv::FONT_HERSHEY_PLAIN, 0.75, colour, 1,
                cv::LINE_AA);
  }
  png_ = perception::encode_png(image);
  png_version_ = v;
  return png_;
}

nlohmann::json DashboardState::json(std::int64_t now_utime) const {
  const std::lock_guard<std::mutex> lock(mutex_);
  nlohmann::json j;
  j["version"] = version_;
  j["domain"] = domain_;
  DomainNames names;
  if (domain_object_) names = domain_object_->names(num_sources_);
  j["names"] = {{"states", names.states},   {"actions", names.actions}, {"features", names.features},
                {"symbols", names.symbols}, {"sources", names.sources}, {"contexts", names.contexts}};
  j["source_colours"] = source_colours_hex();
  j["run"] = {{"episode", episode_},
              {"step", step_},
              {"controlled", controlled_},
              {"ended", run_ended_},
              {"sim_seconds", static_cast<double>(sim_utime_) * 1e-6},
              {"frames", frames_},
              {"episodes_ended", episodes_ended_}};

  // The camera: the latest annotated frame's detections.
  if (frame_) {
    const nlohmann::json detections = detections_json(frame_->detections, frame_->observations, names);
    const auto& d = frame_->detections;
    j["camera"] = {{"episode", std::get<0>(frame_->key)},
                   {"step", std::get<1>(frame_->key)},
                   {"frame", std::get<2>(frame_->key)},
                   {"sim_seconds", static_cast<double>(frame_->utime) * 1e-6},
                   {"width", d.width},
                   {"height", d.height},
                   {"detections", detections}};
  } else {
    j["camera"] = nullptr;
  }
  if (last_observations_) {
    j["observations"] = observation_counts_json(*last_observations_);
  } else {
    j["observations"] = nullptr;
  }

  // Learning: EM iterations, theta, the posterior and the observation model.
  j["em"] = em_json(progress_);
  j["theta"] = theta_json(reward_, progress_, true_weights_);
  j["estimates"] = estimates_json(estimates_);
  j["reward"] =
      reward_ ? nlohmann::json{{"final", reward_->final != 0},
                               {"ile", reward_->ile >= 0.0 ? finite_or_null(reward_->ile) : nlohmann::json(nullptr)},
                               {"log_likelihood", finite_or_null(reward_->log_likelihood)},
                               {"policy", policy_json(*reward_, names)}}
              : nlohmann::json(nullptr);

  if (posterior_) {
    j["posterior"] = posterior_json(*posterior_, truth_);
  } else {
    j["posterior"] = nullptr;
  }
  j["model"] = model_ ? nlohmann::json{{"iteration", model_->iteration},
                                       {"num_states", model_->num_states},
                                       {"num_actions", model_->num_actions},
                                       {"subject", model_->subject},
                                       {"confounders", model_->confounders}}
                      : nlohmann::json(nullptr);
  j["eta"] = model_ && model_->num_contexts > 0 ? eta_panel_json(*model_) : nlohmann::json(nullptr);

  // Service health.
  nlohmann::json services = nlohmann::json::array();
  for (const auto& [id, s] : services_) {
    services.push_back(service_json(id, s.status, s.heard_utime, now_utime));
  }
  j["services"] = services;
  if (!progress_.empty()) {
    j["estep"] = {{"retried_blocks", progress_.back().retries}, {"local_blocks", progress_.back().local_blocks}};
  } else {
    j["estep"] = nullptr;
  }
  return j;
}

}  // namespace hbirl::dashboard
