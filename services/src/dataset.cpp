#include "services/dataset.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <sodium.h>

#include "learner/input_error.hpp"

namespace hbirl::services {

DatasetBuilder::DatasetBuilder() {
  if (sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
  randombytes_buf(digest_key_.data(), digest_key_.size());
}

void DatasetBuilder::subscribe(Bus& bus, Counters& counters) {
  counters_ = &counters;
  // A whole run's messages may be waiting when a replay starts or a slow learner catches up.
  constexpr int kQueue = 1 << 20;
  // A sensor whose every episode or observation is refused cannot make a run: watched.
  // (GROUND_TRUTH is not: a run may have none to accept.)
  const Refusals watched = Refusals::kWatched;
  subs_.add(bus, services::subscribe(
                     bus, channels::kEpisode, counters, [this](const auto& m, const Message&) { on_marker(m); }, kQueue,
                     watched));
  subs_.add(bus, services::subscribe(
                     bus, channels::kObservations, counters,
                     [this](const auto& m, const Message&) { on_observations(m); }, kQueue, watched));
  subs_.add(bus,
            services::subscribe(
                bus, channels::kGroundTruth, counters, [this](const auto& m, const Message&) { on_truth(m); }, kQueue));
}

void DatasetBuilder::expect(const std::string& domain, int num_symbols, int num_sources, int num_states,
                            int num_actions) {
  expected_domain_ = domain;
  expected_symbols_ = num_symbols;
  expected_sources_ = num_sources;
  expected_states_ = num_states;
  expected_actions_ = num_actions;
}

void DatasetBuilder::expect_ends(std::vector<char> terminal, int end_symbols) {
  expected_ends_.emplace(std::move(terminal), end_symbols);
}

namespace {

// What an END_EPISODE marker says of how the episode ended (end_state, -1 when not known,
// and the end sensor's reports), checked against what may be said (`expected`: the
// terminal states and the end alphabet, when known).
std::pair<int, std::vector<int>> seen_end(const hbirl::episode_marker_t& m,
                                          const std::optional<std::pair<std::vector<char>, int>>& expected) {
  std::pair<int, std::vector<int>> out{m.end_state_known ? m.end_state : -1,
                                       std::vector<int>(m.end_report.begin(), m.end_report.end())};
  if (m.controlled && (m.num_end_reports > 0 || m.end_state_known))
    throw InputError(m.end_state_known ? "episode_marker.end_state_known" : "episode_marker.num_end_reports",
                     "a controlled run's end is not used");
  if (!expected) return out;
  const auto& [terminal, end_symbols] = *expected;
  if (out.first >= 0 && (out.first >= static_cast<int>(terminal.size()) || !terminal[static_cast<size_t>(out.first)]))
    throw InputError("episode_marker.end_state", std::to_string(out.first) + " is not a terminal state of the domain");
  if (m.num_end_reports > 0 && m.num_end_symbols != end_symbols) {
    throw InputError("episode_marker.num_end_symbols",
                     std::to_string(m.num_end_symbols) +
                         (end_symbols == 0 ? ", but the domain has no end sensor"
                                           : ", the domain's end sensor has " + std::to_string(end_symbols)));
  }
  return out;
}

}  // namespace

void DatasetBuilder::contradicted(const std::string& why) {
  if (contradiction_.empty()) contradiction_ = why;
}

void DatasetBuilder::saw_episode(int id) {
  last_episode_ = std::max(last_episode_, id);
  if (run_episodes_ > 0 && id >= run_episodes_) {
    contradicted("a message about episode " + std::to_string(id) + " after END_RUN said the run had " +
                 std::to_string(run_episodes_) + " episodes");
  } else if (watching_ && taken_complete_ && !taken_episodes_.count(id)) {  // (an END_RUN that stated no number)
    contradicted("a message about episode " + std::to_string(id) + ", which the run did not have when it was complete");
  }
}

DatasetBuilder::Episode& DatasetBuilder::episode(int id) {
  if (id < 0) throw InputError("episode", "is negative");
  saw_episode(id);
  const auto [it, fresh] = episodes_.try_emplace(id);
  if (fresh && !in_run(id)) ++outside_run_;
  return it->second;
}

// What an episode adds to the run's counts (sign -1 takes it out): the frames and, for a
// controlled episode, the ground-truth steps it lacks, once it has ended and if it belongs
// to the run. The counts are kept as messages come, so that complete() -- asked after
// every message -- does not scan every frame of the run.
void DatasetBuilder::count(const Episode& e, int id, int sign) {
  if (!e.ended || !in_run(id)) return;
  ended_in_run_ += sign;
  const std::int64_t lacking = static_cast<std::int64_t>(e.num_steps) * e.frames_per_step - e.have_frames;
  missing_frames_ += sign * lacking;
  if (!e.controlled && lacking == 0) complete_demonstrations_ += sign;
  if (e.controlled) missing_truth_ += sign * (static_cast<std::int64_t>(e.num_steps) - e.have_truth);
}

// The frames and truth steps an ended episode has within its stated steps and frames.
void DatasetBuilder::recount(Episode& e) {
  e.have_frames = 0;
  for (const auto& [key, f] : e.frames) e.have_frames += key.first < e.num_steps && key.second < e.frames_per_step;
  e.have_truth = 0;
  for (const auto& [step, t] : e.truth) e.have_truth += step < e.num_steps;
}

// Whether an episode belongs to the controlled run is said by its first marker; a later
// one that says otherwise (a stray or forged marker, before or after the sensor's own) is
// refused, not obeyed -- relabelling a controlled episode as a demonstration would change
// what is learned without a word -- and the run contradicts itself.
void DatasetBuilder::mark_controlled(Episode& e, const hbirl::episode_marker_t& m) {
  const bool controlled = m.controlled != 0;
  if (e.marked && e.controlled != controlled) {
    const std::string why = "episode " + std::to_string(m.episode) + " was marked " +
                            (e.controlled ? "controlled" : "a demonstration") + " before: this marker contradicts it";
    contradicted(why);
    throw InputError("episode_marker.controlled", why);
  }
  e.controlled = controlled;
  e.marked = true;
}

void DatasetBuilder::on_marker(const hbirl::episode_marker_t& m) {
  // validate(episode_marker_t) has checked the marker itself (messages.hpp); here, the run.
  if (counters_) counters_->gaps += marker_seq_.see(m.seq);
  if (!expected_domain_.empty() && m.domain != expected_domain_) {
    throw InputError("episode_marker.domain",
                     "'" + m.domain + "' is not the domain learned on ('" + expected_domain_ + "')");
  }
  if (!domain_.empty() && m.domain != domain_)
    throw InputError("episode_marker.domain", "changed from " + domain_ + " to " + m.domain);
  domain_ = m.domain;
  if (watching_) {  // taken: the markers are checked against the run, not kept
    if (m.kind != hbirl::episode_marker_t::END_RUN) {
      watch_marker(m);
      return;
    }
  } else {
    last_utime_ = std::max(last_utime_, m.utime);
  }
  switch (m.kind) {
    case hbirl::episode_marker_t::BEGIN_EPISODE:
    case hbirl::episode_marker_t::BEGIN_STEP:
      on_begin_marker(m);
      break;
    case hbirl::episode_marker_t::END_EPISODE:
      on_end_episode(m);
      break;
    case hbirl::episode_marker_t::END_RUN:
      on_end_run(m);
      break;
    default:
      throw InputError("episode_marker.kind", std::to_string(m.kind) + " is not a marker kind");
  }
}

void DatasetBuilder::on_begin_marker(const hbirl::episode_marker_t& m) {
  Episode& e = episode(m.episode);
  mark_controlled(e, m);
  if (e.frames_per_step != 0 && e.frames_per_step != m.frames_per_step) {
    contradicted("episode " + std::to_string(m.episode) + " stated " + std::to_string(e.frames_per_step) +
                 " frames a step, then " + std::to_string(m.frames_per_step));
  }
  if (e.frames_per_step != m.frames_per_step) {  // (a repeat changes nothing)
    count(e, m.episode, -1);
    e.frames_per_step = m.frames_per_step;
    if (e.ended) recount(e);
    count(e, m.episode, +1);
  }
}

void DatasetBuilder::on_end_episode(const hbirl::episode_marker_t& m) {
  Episode& e = episode(m.episode);
  mark_controlled(e, m);
  // An end marker comes again when it was asked for (FRAME_REQUEST) or replayed: a repeat
  // leaves the counts as they are, without a walk over the episode's frames. An end marker
  // that says otherwise than an earlier one contradicts the run.
  auto [end_state, end_reports] = seen_end(m, expected_ends_);
  if (e.ended &&
      (e.num_steps != m.num_steps || (e.frames_per_step != 0 && e.frames_per_step != m.frames_per_step) ||
       e.ends_in_terminal != m.ends_in_terminal || e.end_state != end_state || e.end_reports != end_reports)) {
    contradicted("episode " + std::to_string(m.episode) + " ended twice, differently (" + std::to_string(e.num_steps) +
                 " then " + std::to_string(m.num_steps) + " steps)");
  }
  // The reports count against --max-dataset-mb as frames do (a marker may hold 1000).
  const std::int64_t report_bytes =
      4 * (static_cast<std::int64_t>(end_reports.size()) - static_cast<std::int64_t>(e.end_reports.size()));
  if (report_bytes > 0 && bytes_ + report_bytes > max_bytes_) {
    throw InputError("episode_marker.num_end_reports", "the run's data would take more than --max-dataset-mb " +
                                                           std::to_string(max_bytes_ >> 20) + " MB: marker not kept");
  }
  bytes_ += report_bytes;
  e.ends_in_terminal = m.ends_in_terminal;
  e.end_state = end_state;
  e.end_reports = std::move(end_reports);
  if (e.ended && e.num_steps == m.num_steps && e.frames_per_step == m.frames_per_step) return;
  count(e, m.episode, -1);
  e.ended = true;
  e.num_steps = m.num_steps;
  e.frames_per_step = m.frames_per_step;
  recount(e);
  count(e, m.episode, +1);
}

void DatasetBuilder::on_end_run(const hbirl::episode_marker_t& m) {
  // A run ends after its episodes: an END_RUN before any ended is not this run's. Once
  // one states the run's number of episodes (num_steps; 0: not stated), episodes 0 .. n-1
  // are the run; a second END_RUN stating another number, or an episode at or past n
  // (begun before or after), contradicts it (docs/RELIABILITY.md).
  end_run_stated_ = std::max(end_run_stated_, m.num_steps);
  const bool any_ended =
      watching_ || std::any_of(episodes_.begin(), episodes_.end(), [](const auto& e) { return e.second.ended; });
  if (!any_ended) throw InputError("episode_marker.kind", "END_RUN before any episode ended: not believed");
  // Without a number, an END_RUN ends the run once the episodes begun have ended: on a bus
  // anyone may publish to, a forger could end it in any pause of the sensor's (and repeat
  // it to pass the confirmation). Believed only when every message is signed.
  if (m.num_steps == 0 && counters_ && !counters_->authenticated) {
    throw InputError("episode_marker.num_steps",
                     "an END_RUN that states no number of episodes is believed only with a run key "
                     "(anyone on an unauthenticated bus could end the run early with one)");
  }
  ++end_runs_heard_;
  if (m.num_steps > 0) {
    if (run_episodes_ > 0 && run_episodes_ != m.num_steps) {
      const std::string why =
          "END_RUN of " + std::to_string(m.num_steps) + " episodes after one of " + std::to_string(run_episodes_);
      contradicted(why);
      throw InputError("episode_marker.num_steps", why);
    }
    if (m.num_steps <= last_episode_) {
      contradicted("END_RUN of " + std::to_string(m.num_steps) + " episodes after a message about episode " +
                   std::to_string(last_episode_));
    }
    if (run_episodes_ == 0 && !watching_) {  // episodes from here on are out of the run: out of its counts too
      for (const auto& [id, e] : episodes_) {
        if (id < m.num_steps) continue;
        count(e, id, -1);
        ++outside_run_;
      }
    }
    run_episodes_ = m.num_steps;
  }
  run_ended_ = true;
}

void DatasetBuilder::on_observations(const hbirl::observations_t& m) {
  if (counters_) counters_->gaps += observation_seq_.see(m.seq);
  // validate(observations_t) has checked the message itself (messages.hpp); here, that it
  // fits the domain and the run.
  if (expected_symbols_ > 0 && m.num_symbols != expected_symbols_) {
    throw InputError("observations.num_symbols",
                     std::to_string(m.num_symbols) + ", the domain has " + std::to_string(expected_symbols_));
  }
  if (expected_sources_ > 0 && m.num_sources != expected_sources_) {
    throw InputError("observations.num_sources", std::to_string(m.num_sources) + " (eta's length), the domain has " +
                                                     std::to_string(expected_sources_) + " sources");
  }
  if (num_symbols_ && (m.num_symbols != num_symbols_ || m.num_sources != num_sources_)) {
    throw InputError("observations.num_sources", "the alphabet or the sources changed mid-run");
  }
  Frame f;
  f.contexts.assign(m.context.begin(), m.context.begin() + m.num_context);
  // Exactly the frame's size: grown by push_back, a frame held up to twice its bytes until
  // the data set was taken (docs/BENCHMARKS.md "Scale to the limit").
  f.symbols.reserve(static_cast<size_t>(m.n));
  f.eta.reserve(static_cast<size_t>(m.n) * static_cast<size_t>(m.num_sources));
  for (int i = 0; i < m.n; ++i) {
    std::vector<double> eta = m.eta[static_cast<size_t>(i)];
    normalise_eta(eta.data(), m.num_sources);  // within its tolerance (validate): rounding brought back to a sum of 1
    f.symbols.push_back(m.symbol[static_cast<size_t>(i)]);
    f.eta.insert(f.eta.end(), eta.begin(), eta.end());
  }
  num_symbols_ = m.num_symbols;
  num_sources_ = m.num_sources;
  if (watching_) {
    watch_frame(m, f);
    return;
  }
  // What the frame costs against --max-dataset-mb, as the data set holds it: a tally
  // refuses what a full builder would (and holds less).
  const std::int64_t bytes = 96 + 4 * static_cast<std::int64_t>(f.symbols.size() + f.contexts.size()) +
                             8 * static_cast<std::int64_t>(f.eta.size());
  if (tally_only_) f = Frame{{}, {}, {}, frame_digest(f)};
  Episode& e = episode(m.episode);
  // A repeat is ignored: the first copy is kept. A frame's observations are the same every
  // time its sensor sends them (perception and the labeller are deterministic): another
  // copy that differs means one of the two is not the sensor's.
  if (const auto seen = e.frames.find({m.step, m.frame}); seen != e.frames.end()) {
    const Frame& first = seen->second;
    if (first.symbols != f.symbols || first.eta != f.eta || first.contexts != f.contexts || first.digest != f.digest) {
      contradicted("two different observations of episode " + std::to_string(m.episode) + ", step " +
                   std::to_string(m.step) + ", frame " + std::to_string(m.frame));
    }
    return;
  }
  if (bytes_ + bytes > max_bytes_) {
    throw InputError("observations", "the run's data would take more than --max-dataset-mb " +
                                         std::to_string(max_bytes_ >> 20) + " MB: frame not kept");
  }
  bytes_ += bytes;
  e.frames.emplace(std::make_pair(m.step, m.frame), std::move(f));
  ++frames_;
  if (e.ended && m.step < e.num_steps && m.frame < e.frames_per_step) {  // a frame that came after its episode's end
    count(e, m.episode, -1);
    ++e.have_frames;
    count(e, m.episode, +1);
  }
  last_utime_ = std::max(last_utime_, m.utime);
}

void DatasetBuilder::on_truth(const hbirl::ground_truth_t& m) {
  // validate(ground_truth_t) has checked the message itself (messages.hpp); here, the run.
  if (counters_) counters_->gaps += truth_seq_.see(m.seq);
  if (expected_states_ > 0 && (m.state >= expected_states_ || m.action >= expected_actions_)) {
    throw InputError("ground_truth.state", "state " + std::to_string(m.state) + " or action " +
                                               std::to_string(m.action) + " is not the domain's");
  }
  if (!domain_.empty() && m.domain != domain_)
    throw InputError("ground_truth.domain", "is " + m.domain + ", the run's " + domain_);
  if (!expected_domain_.empty() && m.domain != expected_domain_) {
    throw InputError("ground_truth.domain",
                     "'" + m.domain + "' is not the domain learned on ('" + expected_domain_ + "')");
  }
  if (watching_) {
    watch_truth(m);
    return;
  }
  Episode& e = episode(m.episode);
  // The first copy of a step's truth is kept, as a frame's is: a later one (a repeat, or
  // a forgery) changes nothing.
  const auto [kept, fresh] = e.truth.try_emplace(m.step, StateAction{m.state, m.action});
  if (!fresh && (kept->second.state != m.state || kept->second.action != m.action)) {
    contradicted("two different ground truths of episode " + std::to_string(m.episode) + ", step " +
                 std::to_string(m.step));
  }
  if (fresh && e.ended && m.step < e.num_steps) {
    ++e.have_truth;
    if (e.controlled && in_run(m.episode)) --missing_truth_;
  }
  // The expert's weights are for the ILE only: weights that disagree with earlier ones
  // leave the ILE unknown; the steps above are kept either way.
  if (m.num_features > 0 && !weights_conflict_) {
    Eigen::VectorXd w = Eigen::Map<const Eigen::VectorXd>(m.true_weights.data(), m.num_features);
    if (true_weights_ && (true_weights_->size() != w.size() || *true_weights_ != w)) {
      weights_conflict_ = true;
      true_weights_.reset();
      if (counters_) counters_->note("ground_truth.true_weights changed mid-run: no ILE for this run");
      return;
    }
    true_weights_ = std::move(w);
  }
}

std::int64_t DatasetBuilder::missing_frames() const { return missing_frames_; }

int DatasetBuilder::unfinished_episodes() const {
  return static_cast<int>(static_cast<std::int64_t>(episodes_.size()) - outside_run_) - ended_in_run_;
}

std::int64_t DatasetBuilder::missing_truth() const { return missing_truth_; }

std::vector<std::tuple<int, int, int>> DatasetBuilder::missing_frame_keys(size_t limit) const {
  std::vector<std::tuple<int, int, int>> out;
  // First the end markers the run lacks (the sensor sends each once; END_RUN says how many
  // episodes there are -- also one not believed yet, end_run_heard() -- else every episode
  // begun is one): nothing of an episode is known complete before its end.
  const auto lacks_end = [this](int id) {
    const auto it = episodes_.find(id);
    return it == episodes_.end() || !it->second.ended;
  };
  const int stated = run_ended_ ? run_episodes_ : end_run_stated_;
  if (stated > 0) {
    for (int id = 0; id < stated && out.size() < limit; ++id) {
      if (lacks_end(id)) out.emplace_back(id, -1, -1);
    }
  } else if (run_ended_) {
    for (const auto& [id, e] : episodes_) {
      if (out.size() >= limit) return out;
      if (!e.ended) out.emplace_back(id, -1, -1);
    }
  }
  for (const auto& [id, e] : episodes_) {
    if (!e.ended || !in_run(id)) continue;
    for (int t = 0; t < e.num_steps; ++t) {
      const bool no_truth = e.controlled && !e.truth.count(t);
      for (int k = 0; k < e.frames_per_step; ++k) {
        if (out.size() >= limit) return out;
        if (!e.frames.count({t, k}) || (k == 0 && no_truth)) out.emplace_back(id, t, k);
      }
    }
  }
  return out;
}

bool DatasetBuilder::complete() const {
  if (!run_ended_) return false;
  // Every episode of the run has ended: when END_RUN said how many there are, all of them
  // (0 .. n-1: ids are distinct), else every episode begun.
  const bool all_ended = run_episodes_ > 0 ? ended_in_run_ == run_episodes_ : unfinished_episodes() == 0;
  return all_ended && missing_frames_ == 0 && missing_truth_ == 0;
}

namespace {

// Contexts are all or none (as in a problem file): when some observations of `set` came
// with contexts and others without, none are kept -- each distinct eta is then a context
// -- and `note` says so. (A frame cannot decide this for the run: the first one might be
// a forgery, and a sensor may give contexts in its demonstrations only.)
void keep_contexts_if_all_given(std::vector<ObservedTrajectory>& set, const std::string& what, std::string& note) {
  bool any = false, all = true;
  for (const auto& t : set) {
    any = any || !t.contexts.empty();
    all = all && (t.num_observations() == 0 || static_cast<int>(t.contexts.size()) == t.num_observations());
  }
  if (!any || all) return;
  for (auto& t : set) t.contexts.clear();
  note += (note.empty() ? "" : "; ") + what +
          ": some observations came with a context and others without: contexts ignored";
}

}  // namespace

Dataset DatasetBuilder::empty_dataset() const {
  Dataset d;
  d.domain = domain_;
  d.num_symbols = num_symbols_;
  d.num_sources = num_sources_;
  d.last_utime = last_utime_;
  d.true_weights = true_weights_;
  return d;
}

void DatasetBuilder::add_episode(Dataset& d, int id, const Episode& e) const {
  if (!e.ended || !in_run(id)) return;
  ObservedTrajectory t;
  t.ends_in_terminal = e.ends_in_terminal;
  t.end_state = e.end_state;
  t.end_symbols = e.end_reports;
  std::vector<double> eta;
  for (int step = 0; step < e.num_steps; ++step) {
    for (auto it = e.frames.lower_bound({step, 0});
         it != e.frames.end() && it->first.first == step && it->first.second < e.frames_per_step; ++it) {
      t.symbols.insert(t.symbols.end(), it->second.symbols.begin(), it->second.symbols.end());
      eta.insert(eta.end(), it->second.eta.begin(), it->second.eta.end());
      t.contexts.insert(t.contexts.end(), it->second.contexts.begin(), it->second.contexts.end());
    }
    t.step_begin.push_back(static_cast<int>(t.symbols.size()));
  }
  t.eta =
      Eigen::Map<const RowMatrix>(eta.data(), static_cast<Eigen::Index>(t.symbols.size()), std::max(1, num_sources_));
  Trajectory truth;
  for (int step = 0; step < e.num_steps; ++step) {
    const auto it = e.truth.find(step);
    if (it == e.truth.end()) break;
    truth.push_back(it->second);
  }
  const bool truth_complete = static_cast<int>(truth.size()) == e.num_steps;
  if (e.controlled) {
    if (!truth_complete) {  // a lost GROUND_TRUTH message: leave the episode out of the prior
      ++d.skipped_controlled;
      return;
    }
    d.controlled_observed.push_back(std::move(t));
    d.controlled_truth.push_back(std::move(truth));
  } else {
    d.episodes.push_back(id);
    d.observed.push_back(std::move(t));
    if (truth_complete) d.truth.push_back(std::move(truth));
  }
}

void DatasetBuilder::finish_dataset(Dataset& d) {
  keep_contexts_if_all_given(d.observed, "demonstrations", d.contexts_note);
  keep_contexts_if_all_given(d.controlled_observed, "controlled run", d.contexts_note);
  if (d.truth.size() != d.observed.size()) d.truth.clear();  // ground truth only when complete
}

int DatasetBuilder::controlled_episodes() const {
  return static_cast<int>(std::count_if(episodes_.begin(), episodes_.end(),
                                        [](const auto& e) { return e.second.marked && e.second.controlled; }));
}

int DatasetBuilder::complete_demonstration_prefix() const {
  int n = 0;
  for (const auto& [id, e] : episodes_) {
    if (!in_run(id) || (e.marked && e.controlled)) continue;
    if (!e.ended || e.have_frames != static_cast<std::int64_t>(e.num_steps) * e.frames_per_step) break;
    ++n;
  }
  return n;
}

Dataset first_demonstrations(Dataset data, size_t n) {
  n = std::min(n, data.observed.size());
  data.observed.resize(n);
  data.episodes.resize(n);
  if (data.truth.size() > n) data.truth.resize(n);
  return data;
}

void DatasetBuilder::tally_only() {
  if (frames_ > 0) throw std::logic_error("DatasetBuilder::tally_only: frames are kept already");
  tally_only_ = true;
}

std::int64_t DatasetBuilder::held_observations() const {
  std::int64_t n = 0;
  for (const auto& [id, e] : episodes_) {
    for (const auto& [key, f] : e.frames) n += static_cast<std::int64_t>(f.symbols.size());
  }
  return n;
}

Dataset DatasetBuilder::build() const {
  if (tally_only_) throw std::logic_error("DatasetBuilder::build: a tally keeps no observations");
  Dataset d = empty_dataset();
  for (const auto& [id, e] : episodes_) add_episode(d, id, e);
  finish_dataset(d);
  return d;
}

// SipHash-2-4 (libsodium's crypto_shorthash) with a key of this builder's, random: a
// forger cannot make a frame that collides with another, as it could with an unkeyed hash.
std::uint64_t DatasetBuilder::frame_digest(const Frame& f) const {
  std::vector<std::uint8_t> bytes;
  const auto add = [&bytes](const void* p, size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    bytes.insert(bytes.end(), b, b + n);
  };
  const std::uint64_t sizes[3] = {f.symbols.size(), f.eta.size(), f.contexts.size()};
  add(sizes, sizeof sizes);
  add(f.symbols.data(), f.symbols.size() * sizeof(int));
  for (double v : f.eta) {
    v += 0.0;  // -0 as +0: equal digests exactly where the frames compare equal (==)
    add(&v, sizeof v);
  }
  add(f.contexts.data(), f.contexts.size() * sizeof(int));
  std::uint64_t out = 0;
  static_assert(crypto_shorthash_BYTES == sizeof out, "an 8-byte digest");
  crypto_shorthash(reinterpret_cast<unsigned char*>(&out), bytes.data(), bytes.size(), digest_key_.data());
  return out;
}

Dataset DatasetBuilder::take() {
  if (tally_only_) throw std::logic_error("DatasetBuilder::take: a tally keeps no observations");
  // A complete run is closed: an episode it did not have contradicts it from now on, and
  // so does an END_RUN stating another number than the episodes 0 .. n-1 it had.
  taken_complete_ = complete();
  if (taken_complete_ && run_episodes_ == 0 && !episodes_.empty() &&
      episodes_.rbegin()->first + 1 == static_cast<int>(episodes_.size())) {
    run_episodes_ = static_cast<int>(episodes_.size());
  }
  Dataset d = empty_dataset();
  // (In order: episodes_ is ordered by episode, each one's frames by step and frame.)
  for (auto& [id, e] : episodes_) {
    add_episode(d, id, e);
    for (const auto& [key, f] : e.frames)
      taken_frames_.emplace_back(std::tuple(id, key.first, key.second), frame_digest(f));
    for (const auto& [step, t] : e.truth) taken_truth_.emplace_back(std::pair(id, step), t);
    e.frames.clear();  // assembled: each observation is held once, here or in d
    e.truth.clear();
  }
  taken_episodes_ = std::move(episodes_);  // their markers, to check later ones against
  episodes_.clear();
  bytes_ = 0;
  missing_frames_ = missing_truth_ = outside_run_ = 0;
  ended_in_run_ = 0;
  complete_demonstrations_ = 0;
  watching_ = true;
  finish_dataset(d);
  return d;
}

// A marker once the data set is taken: about an episode heard of before, it must say what
// that episode's markers said (they are kept, without their frames).
void DatasetBuilder::watch_marker(const hbirl::episode_marker_t& m) {
  if (m.episode < 0) throw InputError("episode", "is negative");
  saw_episode(m.episode);
  const auto it = taken_episodes_.find(m.episode);
  if (it == taken_episodes_.end()) return;  // never heard of before: saw_episode judged it
  Episode& e = it->second;
  mark_controlled(e, m);
  if (e.frames_per_step != 0 && m.frames_per_step != e.frames_per_step) {
    contradicted("episode " + std::to_string(m.episode) + " stated " + std::to_string(e.frames_per_step) +
                 " frames a step, then " + std::to_string(m.frames_per_step));
  }
  if (m.kind == hbirl::episode_marker_t::END_EPISODE && e.ended &&
      (e.num_steps != m.num_steps || e.ends_in_terminal != m.ends_in_terminal ||
       seen_end(m, expected_ends_) != std::pair(e.end_state, e.end_reports))) {
    contradicted("episode " + std::to_string(m.episode) + " ended twice, differently (" + std::to_string(e.num_steps) +
                 " then " + std::to_string(m.num_steps) + " steps)");
  }
}

void DatasetBuilder::watch_frame(const hbirl::observations_t& m, const Frame& f) {
  saw_episode(m.episode);
  const auto key = std::tuple(static_cast<int>(m.episode), static_cast<int>(m.step), static_cast<int>(m.frame));
  const auto it = std::lower_bound(taken_frames_.begin(), taken_frames_.end(), key,
                                   [](const auto& x, const auto& k) { return x.first < k; });
  if (it != taken_frames_.end() && it->first == key && it->second != frame_digest(f)) {
    contradicted("two different observations of episode " + std::to_string(m.episode) + ", step " +
                 std::to_string(m.step) + ", frame " + std::to_string(m.frame));
  }
}

void DatasetBuilder::watch_truth(const hbirl::ground_truth_t& m) {
  if (m.episode < 0) throw InputError("episode", "is negative");
  saw_episode(m.episode);
  const auto key = std::pair(static_cast<int>(m.episode), static_cast<int>(m.step));
  const auto it = std::lower_bound(taken_truth_.begin(), taken_truth_.end(), key,
                                   [](const auto& x, const auto& k) { return x.first < k; });
  if (it != taken_truth_.end() && it->first == key && !(it->second == StateAction{m.state, m.action})) {
    contradicted("two different ground truths of episode " + std::to_string(m.episode) + ", step " +
                 std::to_string(m.step));
  }
}

}  // namespace hbirl::services
