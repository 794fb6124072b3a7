#include "services/estep_service.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <random>
#include <stdexcept>

#include "learner/digest.hpp"
#include "learner/input_error.hpp"
#include "learner/soft_value_iteration.hpp"
#include "services/lcm_arrays.hpp"

namespace hbirl::services {

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

std::uint64_t numerics_fingerprint() {
  static const std::uint64_t fingerprint = [] {
    // Four states in a ring, two actions (stay, or move on with probability 0.7), two
    // symbols, one confounding element, two short observed trajectories.
    std::vector<TransitionEntry> transitions;
    for (int s = 0; s < 4; ++s) {
      transitions.push_back({s, 0, s, 1.0});
      transitions.push_back({s, 1, (s + 1) % 4, 0.7});
      transitions.push_back({s, 1, s, 0.3});
    }
    const Mdp mdp = make_mdp(4, 2, 1, transitions, {{1, 1, 0, 1.0}, {3, 0, 0, 0.5}}, Eigen::Vector4d(0.4, 0.3, 0.2, 0.1), {}, 0.9);
    std::vector<ObservedTrajectory> observed(2);
    const int symbols[2][6] = {{0, 1, 1, 0, 1, 0}, {1, 1, 0, 0, 0, 1}};
    for (int i = 0; i < 2; ++i) {
      observed[static_cast<size_t>(i)].eta.resize(6, 2);
      for (int k = 0; k < 6; ++k) {
        observed[static_cast<size_t>(i)].symbols.push_back(symbols[i][k]);
        observed[static_cast<size_t>(i)].eta.row(k) << 0.3 + 0.1 * k, 0.7 - 0.1 * k;
        if (k % 2 == 1) observed[static_cast<size_t>(i)].step_begin.push_back(k + 1);
      }
    }
    ObservationPrior prior;
    prior.num_symbols = 2;
    prior.num_confounders = 1;
    prior.subject_alpha = Eigen::MatrixXd::Constant(8, 2, 0.5);
    prior.subject_alpha.col(0).array() += Eigen::ArrayXd::LinSpaced(8, 0.1, 3.0);
    prior.confounder_alpha = Eigen::MatrixXd::Ones(1, 2);
    const ObservationEStep estep(mdp, observed, prior, {});
    const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(Eigen::VectorXd::Constant(1, 1.3)));
    const EStepStatistics stats = estep.block_statistics(policy, dirichlet_mean(prior), 1, {0}).front();
    Fnv1a h;  // over the bits of every result
    const auto mix = [&h](const double* x, Eigen::Index n) { h.add(x, static_cast<size_t>(n) * sizeof(double)); };
    mix(policy.log_policy.data(), policy.log_policy.size());
    mix(stats.counts.data(), stats.counts.size());
    mix(stats.alpha_dot.subject.data(), stats.alpha_dot.subject.size());
    mix(stats.alpha_dot.confounders.data(), stats.alpha_dot.confounders.size());
    mix(&stats.log_likelihood, 1);
    return h.value();
  }();
  return fingerprint;
}

hbirl::trajectory_t to_message(const ObservedTrajectory& t, int index, int count, std::uint64_t block_digest,
                               const std::string& worker) {
  hbirl::trajectory_t m{};
  m.utime = 0;  // a data set, not a moment of the demonstration
  m.block_digest = static_cast<std::int64_t>(block_digest);
  m.index = index;
  m.num_trajectories = count;
  m.block_size = ObservationEStep::kBlockSize;
  m.worker = worker;
  m.episode = index;
  m.ends_in_terminal = t.ends_in_terminal;
  m.num_steps = t.length();
  m.step_begin.assign(t.step_begin.begin(), t.step_begin.end() - 1);
  m.n = t.num_observations();
  for (int s : t.symbols) m.symbol.push_back(static_cast<std::int16_t>(s));
  m.num_sources = static_cast<std::int32_t>(t.eta.cols());
  m.eta = lcm_rows(t.eta);
  m.num_weights = static_cast<std::int32_t>(t.weights.size());
  m.weights = t.weights;
  m.num_context = static_cast<std::int32_t>(t.contexts.size());
  m.context = t.contexts;
  return m;
}

ObservedTrajectory from_message(const hbirl::trajectory_t& m) {
  if (m.num_steps < 1) throw InputError("trajectory.num_steps", "must be at least 1");
  if (m.n < 0) throw InputError("trajectory.n", "is negative");
  if (m.num_sources < 1) throw InputError("trajectory.num_sources", "must be at least 1 (the subject)");
  ObservedTrajectory t;
  t.step_begin.assign(m.step_begin.begin(), m.step_begin.end());
  t.step_begin.push_back(m.n);
  if (t.step_begin.front() != 0) throw InputError("trajectory.step_begin[0]", "must be 0");
  for (size_t i = 1; i < t.step_begin.size(); ++i) {
    if (t.step_begin[i] < t.step_begin[i - 1]) {
      throw InputError("trajectory.step_begin[" + std::to_string(i) + "]", "goes backwards or past the observations");
    }
  }
  for (int i = 0; i < m.n; ++i) {
    if (m.symbol[static_cast<size_t>(i)] < 0) throw InputError("trajectory.symbol[" + std::to_string(i) + "]", "is negative");
    t.symbols.push_back(m.symbol[static_cast<size_t>(i)]);
  }
  t.eta = eigen_rows<RowMatrix>(m.eta, m.num_sources);
  for (int i = 0; i < m.n; ++i) {
    const std::string wrong = normalise_eta(t.eta.row(i).data(), m.num_sources);
    if (!wrong.empty()) throw InputError("trajectory.eta[" + std::to_string(i) + "]", wrong);
  }
  if (m.num_weights != 0 && m.num_weights != m.n) throw InputError("trajectory.num_weights", "must be 0 or n");
  for (double w : m.weights) {
    if (!(std::isfinite(w) && w > 0.0)) throw InputError("trajectory.weights", "must be finite and > 0");
  }
  t.weights = m.weights;
  if (m.num_context != 0 && m.num_context != m.n) throw InputError("trajectory.num_context", "must be 0 or n");
  for (int c : m.context) {
    if (c < 0 || c >= kMaxContexts) throw InputError("trajectory.context", std::to_string(c) + " is outside [0, " + std::to_string(kMaxContexts - 1) + "]");
  }
  t.contexts = m.context;
  t.ends_in_terminal = m.ends_in_terminal;
  return t;
}

std::span<const ObservedTrajectory> block_of(const std::vector<ObservedTrajectory>& trajectories, int b) {
  const auto begin = static_cast<size_t>(b) * ObservationEStep::kBlockSize;
  return std::span<const ObservedTrajectory>(trajectories).subspan(begin, std::min<size_t>(ObservationEStep::kBlockSize, trajectories.size() - begin));
}

BusBlockExecutor::BusBlockExecutor(Bus& bus, const Mdp& mdp, const std::string& domain, Counters& counters,
                                   BusExecutorOptions options)
    : bus_(bus),
      mdp_messages_(to_messages(mdp, domain)),
      mdp_digest_(dynamics_digest(mdp)),
      counters_(counters),
      options_(options),
      request_id_(0) {
  // Request ids: random, so that two optimisers on one bus never take each other's answers.
  std::random_device entropy;
  request_id_ = static_cast<std::int64_t>((static_cast<std::uint64_t>(entropy()) << 32 | entropy()) >> 1);
  numerics_ = numerics_fingerprint();
  subs_.add(bus_, subscribe(bus_, channels::kStatus, counters_,
                                                     [this](const hbirl::service_status_t& m, const Message&) { on_status(m); }, 1000));
  // Every block of a pass may arrive between two handle() calls.
  subs_.add(bus_, subscribe(bus_, channels::kEStepResult, counters_,
                                                   [this](const hbirl::estep_result_t& m, const Message&) { on_result(m); }, 100000));
}

void BusBlockExecutor::publish_mdp() const {
  last_mdp_sent_ = Clock::now();
  for (const auto& m : mdp_messages_) publish(bus_, channels::kMdp, m, counters_);
}

// The blocks of the E-step's trajectories as the workers are sent them, and their
// digests; computed again only when the E-step is another (or holds other data).
void BusBlockExecutor::prepare_blocks(const ObservationEStep& estep) const {
  if (prepared_ == &estep && prepared_input_ == estep.input_digest() && prepared_contexts_ == estep.num_contexts() &&
      prepared_kinds_ == estep.uses_kind_table()) {
    return;
  }
  prepared_ = &estep;
  prepared_input_ = estep.input_digest();
  prepared_contexts_ = estep.num_contexts();
  prepared_kinds_ = estep.uses_kind_table();
  block_digests_.clear();
  for (int b = 0; b < estep.num_blocks(); ++b) block_digests_.push_back(dataset_digest(block_of(estep.trajectories(), b)));
  current_blocks_ = std::set<std::uint64_t>(block_digests_.begin(), block_digests_.end());
  data_digest_ = dataset_digest(estep.trajectories());
  if (owner_.size() != block_digests_.size()) owner_.assign(block_digests_.size(), std::string());
  for (auto& [id, w] : workers_) w.unheld.clear();  // what a worker could not hold was of the last data set
}

// Each block of `todo` is queued for the worker `assigned` to it, unless that worker holds
// it (its heartbeat says so) or was sent it less than a timeout ago; then as many are
// sent as the send window takes.
void BusBlockExecutor::send_blocks(const ObservationEStep& estep, const std::vector<int>& todo,
                                   const std::vector<std::string>& assigned) const {
  const auto now = Clock::now();
  const auto resend_after = std::chrono::milliseconds(options_.timeout_ms);
  to_send_.clear();
  for (int b : todo) {
    const std::string& id = assigned[static_cast<size_t>(b)];
    if (id.empty()) continue;
    Worker& w = workers_[id];
    const std::uint64_t digest = block_digests_[static_cast<size_t>(b)];
    if (w.held.count(digest)) continue;
    const auto sent = w.sent.find(digest);
    if (sent != w.sent.end() && now - sent->second.when < resend_after) continue;
    to_send_.emplace_back(b, id);
  }
  pump_blocks(estep);
}

// Bytes sent to workers that no heartbeat has acknowledged yet (less than a timeout ago:
// older ones are taken as lost).
std::int64_t BusBlockExecutor::bytes_in_flight() const {
  const auto now = Clock::now();
  const auto lost_after = std::chrono::milliseconds(options_.timeout_ms);
  std::int64_t bytes = 0;
  for (const auto& [id, w] : workers_) {
    for (const auto& [digest, sent] : w.sent) {
      if (now - sent.when < lost_after) bytes += sent.bytes;
    }
  }
  return bytes;
}

// Sends queued blocks while the window has room (one block at least when nothing is in
// flight, whatever its size).
void BusBlockExecutor::pump_blocks(const ObservationEStep& estep) const {
  if (to_send_.empty()) return;
  std::int64_t in_flight = bytes_in_flight();
  const int n = static_cast<int>(estep.trajectories().size());
  size_t k = 0;
  for (; k < to_send_.size() && (in_flight == 0 || in_flight < options_.send_window_bytes); ++k) {
    const auto& [b, id] = to_send_[k];
    const std::uint64_t digest = block_digests_[static_cast<size_t>(b)];
    const Channel<hbirl::trajectory_t> channel = channels::trajectory_channel(id);
    std::int64_t bytes = 0;
    const int end = std::min(n, (b + 1) * ObservationEStep::kBlockSize);
    for (int i = b * ObservationEStep::kBlockSize; i < end; ++i) {
      const hbirl::trajectory_t m = to_message(estep.trajectories()[static_cast<size_t>(i)], i, n, digest, id);
      publish(bus_, channel, m, counters_);
      bytes += m.getEncodedSize();
    }
    stats_.trajectories_sent += end - b * ObservationEStep::kBlockSize;
    stats_.bytes_sent += bytes;
    workers_[id].sent[digest] = {Clock::now(), bytes};
    in_flight += bytes;
    ++progress_;  // sending goes on: the pass is not stuck
  }
  to_send_.erase(to_send_.begin(), to_send_.begin() + static_cast<std::ptrdiff_t>(k));
}

namespace {
constexpr size_t kMaxWorkers = 4096;  // workers remembered at once (a sender can make up any number of names)

// Two blocks' statistics equal, or within a relative `tolerance` (0: bit for bit).
bool same_statistics(const EStepStatistics& a, const EStepStatistics& b, double tolerance) {
  const auto close = [tolerance](const auto& x, const auto& y) {
    if (x.rows() != y.rows() || x.cols() != y.cols()) return false;
    if (tolerance == 0.0) return x == y;
    return ((x - y).array().abs() <= tolerance * (1.0 + y.array().abs())).all();
  };
  return close(a.counts, b.counts) && close(a.alpha_dot.subject, b.alpha_dot.subject) &&
         close(a.alpha_dot.confounders, b.alpha_dot.confounders) && close(a.source_counts, b.source_counts) &&
         (a.log_likelihood == b.log_likelihood ||
          std::abs(a.log_likelihood - b.log_likelihood) <= tolerance * (1.0 + std::abs(b.log_likelihood))) &&
         a.impossible == b.impossible && close(a.watched, b.watched) &&
         (a.watched_log_likelihood == b.watched_log_likelihood ||
          std::abs(a.watched_log_likelihood - b.watched_log_likelihood) <= tolerance * (1.0 + std::abs(b.watched_log_likelihood)));
}
}  // namespace

void BusBlockExecutor::on_status(const hbirl::service_status_t& m) const {
  if (m.service != "sampler") return;
  if (m.id.empty()) throw InputError("status.id", "is empty");
  if (m.state == "done") {  // a worker on its way out: no more work for it
    workers_.erase(m.id);
    return;
  }
  if (!workers_.count(m.id) && workers_.size() >= kMaxWorkers) {
    // Heartbeats under ever new names: forget the longest silent of those that never
    // answered (a worker that did, busy computing now, is not pushed out by made-up names).
    const auto older = [](const auto& a, const auto& b) {
      return std::pair(a.second.ever_answered, a.second.last_seen) < std::pair(b.second.ever_answered, b.second.last_seen);
    };
    workers_.erase(std::min_element(workers_.begin(), workers_.end(), older));
  }
  Worker& w = workers_[m.id];
  w.mdp_digest = static_cast<std::uint64_t>(m.mdp_digest);
  w.held.clear();
  for (const std::int64_t d : m.held_block) {  // only this data set's blocks: a made-up list takes no memory
    if (!current_blocks_.count(static_cast<std::uint64_t>(d))) continue;
    w.held.insert(static_cast<std::uint64_t>(d));
    progress_ += static_cast<std::int64_t>(w.sent.erase(static_cast<std::uint64_t>(d)));
  }
  // Heard from after it left blocks unanswered: work again, one block until it answers.
  if (w.suspect && Clock::now() > w.suspect_since) w.suspect = false;
  w.last_seen = Clock::now();
  const auto numerics = static_cast<std::uint64_t>(m.numerics);
  if (numerics != numerics_ && other_numerics_.insert(m.id).second) {
    ++stats_.other_numerics;
    counters_.note("sampler " + m.id + " computes with other numerics (fingerprint " + std::to_string(numerics) + ", here " +
                   std::to_string(numerics_) + ")" +
                   (options_.same_numerics_only ? ": it gets no work" : ": theta may differ from a one-process run in the last bits"));
  }
  w.numerics = numerics;
  // A worker without our MDP: send it (not more than twice a second). Its blocks are sent
  // with the pass that gives them to it.
  if (w.mdp_digest != mdp_digest_ && Clock::now() - last_mdp_sent_ > std::chrono::milliseconds(500)) publish_mdp();
}

void BusBlockExecutor::on_result(const hbirl::estep_result_t& m) const {
  if (m.request_id != request_id_ || received_.empty()) {
    ++stats_.stale;
    return;
  }
  if (m.block < 0 || m.block >= blocks_) throw InputError("estep_result.block", std::to_string(m.block) + " is not a block");
  if (static_cast<std::uint64_t>(m.block_digest) != block_digests_[static_cast<size_t>(m.block)]) {  // computed on other trajectories
    ++stats_.foreign;
    return;
  }
  if (m.num_pairs != pairs_ || m.num_symbols != symbols_ || m.num_confounders != confounders_) {
    throw InputError("estep_result.num_pairs", "the statistics have the wrong shape");
  }
  if (!std::isfinite(m.log_likelihood) && m.log_likelihood != -std::numeric_limits<double>::infinity()) {
    throw InputError("estep_result.log_likelihood", "is NaN or +inf");
  }
  auto& slot = received_[static_cast<size_t>(m.block)];
  if (slot && answered_by_[static_cast<size_t>(m.block)] != m.worker) {  // answered already, by the worker it was given to
    ++stats_.duplicates;
    return;
  }
  if (m.worker.empty()) throw InputError("estep_result.worker", "is empty");
  if (!assigned_[static_cast<size_t>(m.block)].count(m.worker)) {  // only the worker given the block is believed
    ++stats_.unassigned;
    throw InputError("estep_result.worker", "'" + m.worker + "' was not given block " + std::to_string(m.block));
  }
  if (workers_[m.worker].distrusted || doubted_.count(m.worker)) {
    throw InputError("estep_result.worker", "'" + m.worker + "' answered wrong: its answers are not used");
  }
  EStepStatistics s = EStepStatistics::zero(pairs_, confounders_, symbols_, contexts_);
  s.counts = eigen_vector(m.counts);
  s.alpha_dot.subject = eigen_rows(m.alpha_subject, symbols_);
  s.alpha_dot.confounders = eigen_rows(m.alpha_confounder, symbols_);
  if (!s.counts.allFinite() || !s.alpha_dot.subject.allFinite() || !s.alpha_dot.confounders.allFinite() ||
      (s.counts.array() < 0).any() || (s.alpha_dot.subject.array() < 0).any() || (s.alpha_dot.confounders.array() < 0).any()) {
    throw InputError("estep_result.counts", "must be finite and >= 0");
  }
  if (m.impossible < 0 || m.impossible > ObservationEStep::kBlockSize) throw InputError("estep_result.impossible", "out of range");
  if (m.num_watched_steps != 0) {  // only from the block that holds the watched trajectory, all its steps
    if (watch_ < 0 || m.block != watch_ / ObservationEStep::kBlockSize || m.num_watched_steps != watch_steps_) {
      throw InputError("estep_result.num_watched_steps", "is not the watched trajectory's length");
    }
    s.watched = eigen_rows<RowMatrix>(m.watched, pairs_);
    const bool distributions = s.watched.allFinite() && (s.watched.array() >= 0.0).all() &&
                               ((s.watched.rowwise().sum().array() - 1.0).abs() <= 1e-6).all();
    if (!distributions) throw InputError("estep_result.watched", "each step's marginals must be a distribution");
    if (!std::isfinite(m.watched_log_likelihood)) throw InputError("estep_result.watched_log_likelihood", "must be finite");
    s.watched_log_likelihood = m.watched_log_likelihood;
  }
  if (m.num_contexts != contexts_ || (contexts_ > 0 && m.num_sources != 1 + confounders_)) {
    throw InputError("estep_result.num_contexts", "is not the request's number of contexts and sources");
  }
  if (m.num_counted < 0 || m.num_counted > contexts_) throw InputError("estep_result.num_counted", "out of range");
  for (int k = 0; k < m.num_counted; ++k) {
    const int c = m.counted_context[static_cast<size_t>(k)];
    if (c < 0 || c >= contexts_ || (k > 0 && c <= m.counted_context[static_cast<size_t>(k) - 1])) {
      throw InputError("estep_result.counted_context", "must be increasing contexts of the request");
    }
    const std::vector<double>& row = m.source_counts[static_cast<size_t>(k)];
    if (!std::all_of(row.begin(), row.end(), [](double x) { return std::isfinite(x) && x >= 0.0; })) {
      throw InputError("estep_result.source_counts", "must be finite and >= 0");
    }
    s.source_counts.row(c) = Eigen::Map<const Eigen::RowVectorXd>(row.data(), static_cast<Eigen::Index>(row.size()));
  }
  s.log_likelihood = m.log_likelihood;
  s.impossible = m.impossible;
  if (slot) {
    // A worker computes a block's bits the same way every time: two different answers
    // under one name mean one is forged (without a run key anyone can use any name), and
    // nothing says which. The blocks answered under that name are computed here this
    // pass; the name keeps its work (a forger must not be able to bench a worker).
    if (!same_statistics(*slot, s, 0.0)) {
      ++stats_.conflicts;
      doubted_.insert(m.worker);
      counters_.bad(channels::kEStepResult.name, "two different answers to block " + std::to_string(m.block) + " under the name '" +
                                                m.worker + "' (one forged?): its blocks of this pass are computed here");
      forget_answers_of(m.worker);
      return;
    }
    ++stats_.duplicates;
    return;
  }
  slot = std::move(s);
  ++progress_;
  answered_.insert(m.worker);
  answered_by_[static_cast<size_t>(m.block)] = m.worker;
  Worker& w = workers_[m.worker];
  w.suspect = false;  // it does answer
  w.ever_answered = true;
  ++w.answers;
  ++stats_.remote_blocks;
}

std::vector<std::string> BusBlockExecutor::live_workers() const {
  std::vector<std::string> out;
  const auto now = Clock::now();
  // Workers that never answered get a trial block each (assignment()) only while the run's
  // budget of passes that waited on such trials lasts.
  const bool trials = stats_.trial_passes < kMaxTrialPasses;
  for (const auto& [id, w] : workers_) {
    if (w.mdp_digest == mdp_digest_ && !w.suspect && !w.distrusted && (trials || w.ever_answered) &&
        (!options_.same_numerics_only || w.numerics == numerics_) &&
        std::chrono::duration<double>(now - w.last_seen).count() <= options_.worker_silence_s) {
      out.push_back(id);
    }
  }
  return out;  // sorted: std::map
}

int BusBlockExecutor::wait_for_workers(int count, int timeout_ms) const {
  const std::lock_guard<std::recursive_mutex> lock(mutex_);
  publish_mdp();
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (static_cast<int>(live_workers().size()) < count && Clock::now() < deadline) {
    if (options_.stop && options_.stop()) break;
    if (options_.idle) options_.idle();
    if (bus_.handle(20) < 0) break;
  }
  return static_cast<int>(live_workers().size());
}

// Blocks to workers, stably: a block stays with the worker it was given to while that
// worker gets work, so each worker is sent its share of the trajectories once; the blocks
// of workers that left, and those over a worker's even share when others join, go to the
// workers under theirs (even shares: sizes differ by at most one block). Except that while
// some workers have proven themselves (answered before), each one that has not gets one
// block, and no more of them than there are proven ones: heartbeats from processes that
// never answer (a crashed build, a forger) cost a pass one timeout, not the whole pass.
// A block a worker failed to hold twice goes to another (none can: computed here), and a
// worker that failed to hold two and holds none gets nothing -- a block it cannot hold would
// cost every pass it is given in a timeout -- for this data set, or until a minute passes
// without such a failure (Worker::unheld).
std::vector<std::string> BusBlockExecutor::assignment(const std::vector<int>& todo, std::vector<std::string> workers) const {
  for (const auto& w : workers) {  // failures to hold are forgotten a minute after the last
    Worker& x = workers_.at(w);
    if (!x.unheld.empty() && Clock::now() - x.last_unheld > std::chrono::minutes(1)) x.unheld.clear();
  }
  const auto can_hold = [this](const std::string& w, int b) {
    return workers_.at(w).can_hold(block_digests_[static_cast<size_t>(b)]);
  };
  // A worker that failed to hold two blocks and holds none gets no more (for this data set,
  // or until the minute above passes): each block it is given would cost the pass a timeout.
  workers.erase(std::remove_if(workers.begin(), workers.end(),
                               [this](const std::string& w) {
                                 const Worker& x = workers_.at(w);
                                 return x.blocks_it_cannot_hold() >= 2 && x.held.empty();
                               }),
                workers.end());
  std::vector<std::string> proven, unproven;
  for (const auto& w : workers) (workers_.at(w).answers > 0 ? proven : unproven).push_back(w);
  std::vector<std::string> out(static_cast<size_t>(blocks_));
  std::vector<int> rest = todo;
  if (!proven.empty()) {
    unproven.resize(std::min(unproven.size(), proven.size()));
    for (const auto& w : unproven) {  // the block it has, else the last one; either one it can hold
      if (rest.empty()) break;
      auto pick = std::find_if(rest.begin(), rest.end(), [&](int b) { return owner_[static_cast<size_t>(b)] == w && can_hold(w, b); });
      if (pick == rest.end()) {
        const auto last = std::find_if(rest.rbegin(), rest.rend(), [&](int b) { return can_hold(w, b); });
        if (last == rest.rend()) continue;
        pick = std::prev(last.base());
      }
      out[static_cast<size_t>(*pick)] = w;
      rest.erase(pick);
    }
    workers = proven;
  }
  const size_t n = workers.size();
  std::map<std::string, size_t> share, given;  // even shares, the first ones one larger
  for (size_t k = 0; k < n; ++k) share[workers[k]] = rest.size() / n + (k < rest.size() % n ? 1 : 0);  // none: all loose
  std::vector<int> loose;
  for (int b : rest) {
    const std::string& owner = owner_[static_cast<size_t>(b)];
    const auto it = share.find(owner);
    if (it != share.end() && given[owner] < it->second && can_hold(owner, b)) {
      out[static_cast<size_t>(b)] = owner;
      ++given[owner];
    } else {
      loose.push_back(b);
    }
  }
  for (int b : loose) {  // the first worker under its share that can hold it, else the least loaded that can
    std::string pick;
    for (const auto& w : workers) {
      if (!can_hold(w, b)) continue;
      if (given[w] < share[w]) {
        pick = w;
        break;
      }
      if (pick.empty() || given[w] < given[pick]) pick = w;
    }
    if (pick.empty()) continue;  // no worker can: computed here
    out[static_cast<size_t>(b)] = pick;
    ++given[pick];
  }
  for (int b : todo) {  // a block moved: its old worker drops it (sampler_worker.hpp)
    std::string& owner = owner_[static_cast<size_t>(b)];
    const std::string& now = out[static_cast<size_t>(b)];
    if (owner == now) continue;
    const auto old = workers_.find(owner);
    if (old != workers_.end()) {
      old->second.held.erase(block_digests_[static_cast<size_t>(b)]);
      old->second.sent.erase(block_digests_[static_cast<size_t>(b)]);
    }
    owner = now;
  }
  return out;
}

// The blocks spot-checked this pass: one block, at random, of each worker never checked
// (a worker that always lies is caught before any of its answers is used; it costs one
// block per worker once), or, once all are, one block at random (a worker that lies now
// and then is caught in time, never by construction). Unpredictable to the workers.
std::vector<int> BusBlockExecutor::spot_blocks(const std::vector<int>& todo, const std::vector<std::string>& assigned) const {
  std::map<std::string, std::vector<int>> unchecked;  // worker -> its blocks
  for (int b : todo) {
    const std::string& w = assigned[static_cast<size_t>(b)];
    if (!w.empty() && !workers_[w].checked) unchecked[w].push_back(b);
  }
  std::vector<int> out;
  for (const auto& [w, blocks] : unchecked) out.push_back(blocks[static_cast<size_t>(spot_rng_() % blocks.size())]);
  if (out.empty() && !todo.empty()) out.push_back(todo[static_cast<size_t>(spot_rng_() % todo.size())]);
  return out;
}

// The spot check: the block's answer against the one computed here. Workers that compute
// with the same numerics give the same bits; others (--same-numerics-only off) may differ
// in the last bits, so they are held to a relative 1e-9.
void BusBlockExecutor::check_spot(int block, const EStepStatistics& here) const {
  const std::string worker = answered_by_[static_cast<size_t>(block)];
  const auto it = workers_.find(worker);
  const double tolerance = it != workers_.end() && it->second.numerics == numerics_ ? 0.0 : 1e-9;
  if (same_statistics(*received_[static_cast<size_t>(block)], here, tolerance)) {
    workers_[worker].checked = true;
    return;
  }
  distrust(worker, "answered block " + std::to_string(block) + " unlike the optimiser's own computation");
  received_[static_cast<size_t>(block)] = here;
  ++stats_.local_blocks;
}

// A worker caught answering wrong: no more work, no more of its answers, and every block
// it answered in this pass is computed again.
void BusBlockExecutor::distrust(const std::string& worker, const std::string& why) const {
  ++stats_.liars;
  workers_[worker].distrusted = true;
  counters_.bad(channels::kEStepResult.name,
                "worker '" + worker + "' " + why + ": it gets no more work, and its blocks of this pass are computed here");
  forget_answers_of(worker);
}

// The blocks `worker` answered in this pass are missing again (computed here, or by
// another worker in a later attempt).
void BusBlockExecutor::forget_answers_of(const std::string& worker) const {
  for (int b = 0; b < blocks_; ++b) {
    if (answered_by_[static_cast<size_t>(b)] != worker) continue;
    received_[static_cast<size_t>(b)].reset();
    answered_by_[static_cast<size_t>(b)].clear();
    --stats_.remote_blocks;
  }
}

BusBlockExecutor::Stats BusBlockExecutor::stats() const {
  const std::lock_guard<std::recursive_mutex> lock(mutex_);
  return stats_;
}

std::vector<EStepStatistics> BusBlockExecutor::run(const ObservationEStep& estep, const SoftSolution& policy,
                                                   const ObservationModel& model, std::uint64_t seed, const RowMatrix* eta) const {
  const std::lock_guard<std::recursive_mutex> lock(mutex_);
  if (options_.stop && options_.stop()) throw Stopped();
  const auto start = Clock::now();
  // First what came while the optimiser was busy elsewhere (heartbeats above all: who is
  // live is decided from them). Bounded, so a flood cannot hold the pass up.
  for (int k = 0; k < 100000 && bus_.handle(0) > 0; ++k) {
  }
  // The workers compute with the exact engine on this executor's MDP: the pass must too.
  if (dynamics_digest(estep.mdp()) != mdp_digest_) throw std::logic_error("BusBlockExecutor: the E-step's MDP is not the workers'");
  if (!estep.options().engine(estep.mdp())->exact()) throw std::logic_error("BusBlockExecutor: workers run the exact engine only");
  ++request_id_;
  ++stats_.requests;
  blocks_ = estep.num_blocks();
  pairs_ = estep.mdp().num_pairs();
  symbols_ = model.num_symbols();
  confounders_ = model.num_confounders();
  contexts_ = eta ? static_cast<int>(eta->rows()) : 0;
  if (eta && (eta->rows() != estep.num_contexts() || eta->cols() != 1 + confounders_)) {
    throw std::logic_error("BusBlockExecutor: learned eta does not have one row per context and a column per source");
  }
  if (contexts_ > options_.max_contexts) {
    // A sensor without contexts whose every eta differs has about one context per
    // observation: each pass would send them all to every worker. Computed here instead.
    if (!said_too_many_contexts_) {
      counters_.note("learned eta has " + std::to_string(contexts_) + " contexts (each distinct eta is one), more than the " +
                     std::to_string(options_.max_contexts) + " a request carries: the E-step is computed here, not by the workers "
                     "(give the observations contexts, or --eta stated)");
      said_too_many_contexts_ = true;
    }
    std::vector<int> all(static_cast<size_t>(blocks_));
    for (int b = 0; b < blocks_; ++b) all[static_cast<size_t>(b)] = b;
    stats_.local_blocks += blocks_;
    return estep.block_statistics(policy, model, seed, all, options_.local_threads, eta);
  }
  prepare_blocks(estep);
  received_.assign(static_cast<size_t>(blocks_), std::nullopt);
  answered_.clear();
  assigned_.assign(static_cast<size_t>(blocks_), {});
  answered_by_.assign(static_cast<size_t>(blocks_), std::string());
  doubted_.clear();
  std::vector<int> spots;  // the blocks checked here this pass, and their statistics
  std::vector<EStepStatistics> spot_results;
  std::vector<std::string> spot_workers;  // whom each spot block was given to

  hbirl::estep_request_t request{};
  request.utime = 0;
  request.request_id = request_id_;
  request.dataset_digest = static_cast<std::int64_t>(data_digest_);
  request.mdp_digest = static_cast<std::int64_t>(mdp_digest_);
  request.num_trajectories = static_cast<std::int32_t>(estep.trajectories().size());
  request.block_size = ObservationEStep::kBlockSize;
  request.num_blocks = blocks_;
  for (const std::uint64_t d : block_digests_) request.block_digest.push_back(static_cast<std::int64_t>(d));
  request.kind_table = estep.uses_kind_table();
  request.seed = static_cast<std::int64_t>(seed);
  request.engine = "exact";
  request.max_kinds = estep.options().max_kinds;
  request.watch = estep.options().watch;
  watch_ = request.watch;
  watch_steps_ = watch_ >= 0 ? estep.trajectories()[static_cast<size_t>(watch_)].length() : 0;
  request.num_pairs = pairs_;
  request.log_policy = lcm_vector(policy.log_policy);
  request.policy = lcm_vector(policy.policy);
  request.num_symbols = symbols_;
  request.num_confounders = confounders_;
  request.subject_o = lcm_rows(model.subject);
  request.confounder_o = lcm_rows(model.confounders);
  request.num_contexts = contexts_;
  request.num_sources = 1 + confounders_;
  if (eta) request.context_eta = lcm_rows(*eta);

  const auto missing = [this] {
    std::vector<int> out;
    for (int b = 0; b < blocks_; ++b) {
      if (!received_[static_cast<size_t>(b)]) out.push_back(b);
    }
    return out;
  };
  for (int attempt = 0; attempt < options_.max_attempts; ++attempt) {
    std::vector<int> todo = missing();
    if (todo.empty()) break;
    // First attempt: every live worker. Later ones: those that answered this request.
    std::vector<std::string> workers = live_workers();
    workers.erase(std::remove_if(workers.begin(), workers.end(), [this](const std::string& w) { return doubted_.count(w) > 0; }),
                  workers.end());
    if (attempt > 0) {
      std::vector<std::string> proven;
      for (const auto& w : workers) {
        if (answered_.count(w)) proven.push_back(w);
      }
      if (!proven.empty()) workers = proven;
    }
    if (workers.empty()) break;
    if (attempt > 0) stats_.retried_blocks += static_cast<std::int64_t>(todo.size());
    ++stats_.attempts;
    request.attempt = attempt;
    request.assigned_worker = assignment(todo, workers);
    for (int b : todo) {  // a block given to nobody (none can hold it) is computed here: no answer to it is believed
      const std::string& w = request.assigned_worker[static_cast<size_t>(b)];
      if (!w.empty()) assigned_[static_cast<size_t>(b)].insert(w);
    }
    send_blocks(estep, todo, request.assigned_worker);
    publish(bus_, channels::kEStepRequest, request, counters_);
    if (attempt == 0 && options_.spot_check) {  // computed here while the workers compute the rest
      spots = spot_blocks(todo, request.assigned_worker);
      for (int b : spots) spot_workers.push_back(request.assigned_worker[static_cast<size_t>(b)]);
      spot_results = estep.block_statistics(policy, model, seed, spots, options_.local_threads, eta);
      stats_.spot_checks += static_cast<std::int64_t>(spots.size());
    }
    // Waiting ends a timeout after the last progress (an answer, a block acknowledged):
    // a worker still receiving its share or computing a long block is not re-asked.
    auto deadline = Clock::now() + std::chrono::milliseconds(options_.timeout_ms);
    std::int64_t seen = progress_;
    // Waiting is pointless once every missing block is a refused worker's.
    const auto awaited = [&] {
      for (int b : missing()) {
        const std::string& w = request.assigned_worker[static_cast<size_t>(b)];
        if (!w.empty() && !doubted_.count(w) && !workers_[w].distrusted) return true;
      }
      return false;
    };
    while (!missing().empty() && awaited() && Clock::now() < deadline) {
      if (options_.stop && options_.stop()) throw Stopped();
      if (options_.idle) options_.idle();
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (bus_.handle(static_cast<int>(std::clamp<long long>(left, 0, 50))) < 0) break;
      pump_blocks(estep);
      if (progress_ != seen) {
        seen = progress_;
        deadline = Clock::now() + std::chrono::milliseconds(options_.timeout_ms);
      }
    }
    // Workers with blocks still queued were not given the chance to answer: not their fault.
    bool trial_failed = false;
    std::set<std::string> queued;
    for (const auto& [b, id] : to_send_) queued.insert(id);
    to_send_.clear();  // what is still queued goes with the next attempt, to whoever gets it
    for (int b : missing()) {
      const std::string& w = request.assigned_worker[static_cast<size_t>(b)];
      if (w.empty() || queued.count(w)) continue;
      // Sent, and a heartbeat since that says it is not held: counted; twice, and the block
      // goes to others. (A worker busy computing sends no heartbeat: no strike. A name whose
      // answers are doubted is not judged by what may be a forger's heartbeats.)
      Worker& x = workers_[w];
      const std::uint64_t digest = block_digests_[static_cast<size_t>(b)];
      const auto sent = x.sent.find(digest);
      if (sent != x.sent.end() && x.last_seen > sent->second.when && !x.held.count(digest) && !doubted_.count(w) &&
          !x.distrusted) {
        x.last_unheld = Clock::now();
        ++x.unheld[digest];
      }
      // Workers that left blocks unanswered get no more work until they are heard from again
      // (a worker that missed a request works again). A pass that waited on one that never
      // answered at all counts against the run's budget of such passes: made-up workers,
      // whatever their number and the rate of their heartbeats, cost at most
      // kMaxTrialPasses timeouts in all.
      if (answered_.count(w)) continue;
      trial_failed = trial_failed || !x.ever_answered;
      Worker& silent = x;
      silent.suspect = true;
      silent.suspect_since = Clock::now();
      silent.answers = 0;  // once heard from again it gets one block until it answers
    }
    stats_.trial_passes += trial_failed;
  }
  for (size_t k = 0; k < spots.size(); ++k) {
    auto& slot = received_[static_cast<size_t>(spots[k])];
    if (slot) {
      check_spot(spots[k], spot_results[k]);
    } else {
      slot = std::move(spot_results[k]);  // not answered: computed here already
      ++stats_.local_blocks;
    }
    // A worker never checked that left its checked block to someone else: none of its
    // answers of this pass was checked, so none is used.
    const auto meant = workers_.find(spot_workers[k]);
    if (meant != workers_.end() && !meant->second.checked && !meant->second.distrusted) forget_answers_of(spot_workers[k]);
  }
  const std::vector<int> rest = missing();
  if (!rest.empty()) {
    const std::vector<EStepStatistics> local = estep.block_statistics(policy, model, seed, rest, options_.local_threads, eta);
    for (size_t k = 0; k < rest.size(); ++k) received_[static_cast<size_t>(rest[k])] = local[k];
    stats_.local_blocks += static_cast<std::int64_t>(rest.size());
  }
  std::vector<EStepStatistics> out;
  out.reserve(received_.size());
  for (auto& s : received_) out.push_back(std::move(*s));
  received_.clear();  // answers from now on are stale
  stats_.round_trip_s += std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

}  // namespace hbirl::services
