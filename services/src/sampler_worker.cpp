// The sampler worker service (sampler_worker.hpp).
#include "services/sampler_worker.hpp"

#include <algorithm>

#include "learner/input_error.hpp"
#include "services/lcm_arrays.hpp"

namespace hbirl::services {

namespace {

using Clock = std::chrono::steady_clock;

// What one received trajectory takes once held (its arrays as decoded, plus the
// bookkeeping of a map node): what --max-dataset-mb counts.
std::int64_t held_bytes(const hbirl::trajectory_t& m) {
  return 256 + 4 * static_cast<std::int64_t>(m.step_begin.size()) + 4 * static_cast<std::int64_t>(m.symbol.size()) +
         8 * static_cast<std::int64_t>(m.n) * std::max(1, m.num_sources) + 8 * static_cast<std::int64_t>(m.weights.size()) +
         4 * static_cast<std::int64_t>(m.context.size());
}

}  // namespace

SamplerWorker::SamplerWorker(Bus& bus, std::string id, Counters& counters, std::int64_t max_dataset_bytes)
    : bus_(bus), id_(std::move(id)), counters_(counters), max_dataset_bytes_(max_dataset_bytes) {
  subs_.add(bus_, subscribe<hbirl::mdp_t>(bus_, channels::kMdp, counters_,
                                          [this](const hbirl::mdp_t& m, const Message&) { on_mdp(m); }, 10000));
  // A whole data set may arrive between two handle() calls; only the newest requests matter.
  subs_.add(bus_, subscribe<hbirl::trajectory_t>(bus_, channels::kTrajectory, counters_,
                                                 [this](const hbirl::trajectory_t& m, const Message&) { on_trajectory(m); }, 100000));
  subs_.add(bus_, subscribe<hbirl::estep_request_t>(bus_, channels::kEStepRequest, counters_,
                                                    [this](const hbirl::estep_request_t& m, const Message&) { on_request(m); }, 8));
}

int SamplerWorker::handle(int timeout_ms) {
  if (Clock::now() >= next_status_) {
    publish_status();
    next_status_ = Clock::now() + std::chrono::seconds(1);
  }
  return bus_.handle(timeout_ms);
}

void SamplerWorker::publish_status(const std::string& state) {
  hbirl::service_status_t s{};
  s.utime = wall_utime();
  s.service = "sampler";
  s.id = id_;
  s.seq = ++status_seq_;
  s.state = !state.empty() ? state : trajectories_.empty() ? "starting" : "running";
  s.messages_in = counters_.messages_in;
  s.messages_out = counters_.messages_out;
  s.bad_messages = counters_.bad_messages;
  s.gaps = counters_.gaps;
  s.trajectories = static_cast<std::int32_t>(trajectories_.size());
  s.dataset_digest = static_cast<std::int64_t>(digest_);
  s.numerics = static_cast<std::int64_t>(numerics_fingerprint());
  s.mdp_digest = static_cast<std::int64_t>(mdp_digest_.load());
  s.detail = counters_.last_problem;
  s.authenticated = counters_.authenticated;
  s.restarts = counters_.restarts;
  publish(bus_, channels::kStatus, s, counters_);
}

void SamplerWorker::on_mdp(const hbirl::mdp_t& m) {
  if (static_cast<std::uint64_t>(m.mdp_digest) == mdp_digest_ && mdp_) return;  // have it already
  std::optional<Mdp> mdp = incoming_mdp_.add(m);
  if (!mdp) return;
  estep_.reset();  // it computes on the old MDP
  mdp_ = std::move(mdp);
  mdp_digest_ = static_cast<std::uint64_t>(m.mdp_digest);
  publish_status();  // tell the optimiser at once
}

void SamplerWorker::on_trajectory(const hbirl::trajectory_t& m) {
  if (m.num_trajectories < 1 || m.index < 0 || m.index >= m.num_trajectories) {
    throw InputError("trajectory.index", std::to_string(m.index) + " is not in [0, " + std::to_string(m.num_trajectories) + ")");
  }
  const auto d = static_cast<std::uint64_t>(m.dataset_digest);
  if (d == digest_ && !trajectories_.empty()) return;  // have it already
  if (d != incoming_digest_ || incoming_size_ != m.num_trajectories) {
    std::map<int, ObservedTrajectory>().swap(incoming_);
    incoming_digest_ = d;
    incoming_size_ = m.num_trajectories;
    incoming_bytes_ = 0;
  }
  if (incoming_.count(m.index)) return;  // a repeat
  const std::int64_t bytes = held_bytes(m);
  if (incoming_bytes_ + bytes > max_dataset_bytes_) {
    std::map<int, ObservedTrajectory>().swap(incoming_);
    incoming_digest_ = 0;
    throw InputError("trajectory", "the data set would take more than --max-dataset-mb " +
                                       std::to_string(max_dataset_bytes_ >> 20) + " MB: dropped");
  }
  incoming_.emplace(m.index, from_message(m));
  incoming_bytes_ += bytes;
  if (static_cast<int>(incoming_.size()) < incoming_size_) return;
  std::vector<ObservedTrajectory> all;
  all.reserve(incoming_.size());
  for (auto& [index, t] : incoming_) all.push_back(std::move(t));
  std::map<int, ObservedTrajectory>().swap(incoming_);
  incoming_digest_ = 0;
  if (dataset_digest(all) != d) throw InputError("trajectory.dataset_digest", "does not match the trajectories received");
  trajectories_ = std::move(all);
  max_symbol_ = -1;
  for (const auto& t : trajectories_) {
    for (int w : t.symbols) max_symbol_ = std::max(max_symbol_, w);
  }
  digest_ = d;
  estep_.reset();
  publish_status();  // tell the optimiser at once
}

void SamplerWorker::on_request(const hbirl::estep_request_t& m) {
  if (!answered_.insert({m.request_id, m.attempt}).second) return;  // a repeat: answered already
  while (answered_.size() > 256) answered_.erase(answered_.begin());
  if (static_cast<std::uint64_t>(m.dataset_digest) != digest_ || trajectories_.empty() ||
      static_cast<std::uint64_t>(m.mdp_digest) != mdp_digest_ || !mdp_) {
    publish_status();  // the optimiser sees our digests and sends its MDP and data set
    return;
  }
  std::vector<int> mine;
  for (int b = 0; b < m.num_blocks; ++b) {
    if (m.assigned_worker[static_cast<size_t>(b)] == id_) mine.push_back(b);
  }
  if (mine.empty()) return;
  const int P = mdp_->num_pairs(), W = m.num_symbols, E = m.num_confounders;
  if (m.engine != "exact") throw InputError("estep_request.engine", "'" + m.engine + "' is not an engine this worker has");
  if (m.num_pairs != P) throw InputError("estep_request.num_pairs", "is not the MDP's |S||A| = " + std::to_string(P));
  if (m.block_size != ObservationEStep::kBlockSize) throw InputError("estep_request.block_size", "differs from this worker's");
  if (m.num_trajectories != static_cast<int>(trajectories_.size())) throw InputError("estep_request.num_trajectories", "differs");
  if (W < 1 || E < 0) throw InputError("estep_request.num_symbols", "must be >= 1 (and num_confounders >= 0)");
  if (max_symbol_ >= W) throw InputError("estep_request.num_symbols", "is smaller than the data set's alphabet");
  for (const auto& t : trajectories_) {
    if (t.num_observations() > 0 && t.eta.cols() != 1 + E) throw InputError("estep_request.num_confounders", "does not fit the data set's eta");
  }
  if (m.watch < -1 || m.watch >= m.num_trajectories) throw InputError("estep_request.watch", "is not a trajectory of the data set");
  // (Each distinct eta may be a context: their number is checked against the data set's below.)
  if (m.num_contexts < 0) throw InputError("estep_request.num_contexts", "is negative");
  const bool learned_eta = m.num_contexts > 0;
  if (learned_eta && (E < 1 || m.num_sources != 1 + E)) {
    throw InputError("estep_request.num_sources", "learned eta needs 1 + num_confounders sources and a confounder");
  }
  if (!estep_ || estep_symbols_ != W || estep_confounders_ != E || estep_->options().max_kinds != m.max_kinds ||
      estep_->options().watch != m.watch || estep_->prior().learn_eta != learned_eta) {
    // The worker never refines alpha or eta: only the prior's shape matters here, and with
    // learned eta that it numbers the data's contexts as the optimiser's E-step does.
    ObservationPrior shape;
    shape.learn_eta = learned_eta;
    shape.num_symbols = W;
    shape.num_confounders = E;
    shape.subject_alpha = Eigen::MatrixXd::Ones(P, W);
    shape.confounder_alpha = Eigen::MatrixXd::Ones(E, W);
    ObservationEStepOptions options;
    options.max_kinds = m.max_kinds;
    options.watch = m.watch;
    estep_.emplace(*mdp_, trajectories_, shape, options);
    estep_symbols_ = W;
    estep_confounders_ = E;
  }
  if (m.num_blocks != estep_->num_blocks()) throw InputError("estep_request.num_blocks", "differs from this worker's");
  SoftSolution policy;
  policy.log_policy = eigen_vector(m.log_policy);
  policy.policy = eigen_vector(m.policy);
  ObservationModel model;
  model.subject = eigen_rows(m.subject_o, W);
  model.confounders = eigen_rows(m.confounder_o, W);
  if (!model.subject.allFinite() || !model.confounders.allFinite() || (model.subject.array() < 0).any() ||
      (model.confounders.array() < 0).any()) {
    throw InputError("estep_request.subject_o", "the observation model must be finite and >= 0");
  }
  std::optional<RowMatrix> eta;
  if (learned_eta) {
    if (m.num_contexts != estep_->num_contexts()) {
      throw InputError("estep_request.num_contexts", std::to_string(m.num_contexts) + ", the data set has " +
                                                         std::to_string(estep_->num_contexts()) + " contexts");
    }
    eta = eigen_rows<RowMatrix>(m.context_eta, m.num_sources);
    if (!eta->allFinite() || (eta->array() < 0).any()) throw InputError("estep_request.context_eta", "must be finite and >= 0");
  }
  // One block at a time, each answer sent as soon as it is ready.
  for (const int block : mine) {
    const auto start = Clock::now();
    const EStepStatistics s =
        estep_->block_statistics(policy, model, static_cast<std::uint64_t>(m.seed), {block}, 1, eta ? &*eta : nullptr).front();
    hbirl::estep_result_t r{};
    r.utime = m.utime;
    r.request_id = m.request_id;
    r.worker = id_;
    r.dataset_digest = static_cast<std::int64_t>(digest_);
    r.block = block;
    r.num_pairs = P;
    r.counts = lcm_vector(s.counts);
    if (lying_ && !r.counts.empty()) r.counts[0] += 1.0;
    r.num_symbols = W;
    r.num_confounders = E;
    r.alpha_subject = lcm_rows(s.alpha_dot.subject);
    r.alpha_confounder = lcm_rows(s.alpha_dot.confounders);
    r.log_likelihood = s.log_likelihood;
    r.impossible = s.impossible;
    r.compute_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    r.num_watched_steps = static_cast<std::int32_t>(s.watched.rows());
    r.watched = lcm_rows(s.watched);
    r.watched_log_likelihood = s.watched_log_likelihood;
    r.num_contexts = learned_eta ? m.num_contexts : 0;
    r.num_sources = learned_eta ? m.num_sources : 0;
    for (Eigen::Index c = 0; c < s.source_counts.rows(); ++c) {  // only the contexts the block has
      if ((s.source_counts.row(c).array() == 0.0).all()) continue;
      r.counted_context.push_back(static_cast<std::int32_t>(c));
      r.source_counts.emplace_back(s.source_counts.row(c).begin(), s.source_counts.row(c).end());
    }
    r.num_counted = static_cast<std::int32_t>(r.counted_context.size());
    publish(bus_, channels::kEStepResult, r, counters_);
    ++blocks_computed_;
  }
}

}  // namespace hbirl::services
