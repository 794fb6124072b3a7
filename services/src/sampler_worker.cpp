// The sampler worker service (sampler_worker.hpp).
#include "services/sampler_worker.hpp"

#include <algorithm>

#include "learner/input_error.hpp"
#include "services/lcm_arrays.hpp"
#include "services/process.hpp"

namespace hbirl::services {

namespace {

using Clock = std::chrono::steady_clock;

// What one received trajectory takes once held (its arrays as decoded, plus the
// bookkeeping of a map node): what --max-dataset-mb counts.
std::int64_t held_bytes(const hbirl::trajectory_t& m) {
  return 256 + 4 * static_cast<std::int64_t>(m.step_begin.size()) + 4 * static_cast<std::int64_t>(m.symbol.size()) +
         8 * static_cast<std::int64_t>(m.n) * std::max(1, m.num_sources) +
         8 * static_cast<std::int64_t>(m.weights.size()) + 4 * static_cast<std::int64_t>(m.context.size());
}

// Blocks being received at once: a sender making up digests cannot make the list grow.
constexpr size_t kMaxIncomingBlocks = 4096;
// A pending request's blocks that are here are computed once no trajectory has come for
// this long (the rest may have been lost: the optimiser re-asks them elsewhere).
constexpr auto kQuietBeforeServing = std::chrono::milliseconds(200);

// The held blocks a request assigns this worker, in block order -- local block k is the
// k-th of them, so every one but the last must be a whole block -- with the watched
// trajectory's local index (-1: not here) and how many trajectories they hold.
struct LocalBlocks {
  std::vector<std::pair<int, std::uint64_t>> blocks;  // (block, digest)
  int watch = -1;
  size_t trajectories = 0;
};

// `size(digest)`: the trajectories of a held block (0: not held).
template <class Size>
LocalBlocks local_blocks(const hbirl::estep_request_t& m, const std::map<int, std::uint64_t>& assigned,
                         const Size& size) {
  LocalBlocks out;
  for (const auto& [b, digest] : assigned) {
    const size_t n = size(digest);
    if (n == 0) continue;
    if (!out.blocks.empty() && size(out.blocks.back().second) != static_cast<size_t>(ObservationEStep::kBlockSize)) {
      throw InputError("estep_request.block_digest", "puts a short block before others");
    }
    if (m.watch >= 0 && m.watch / ObservationEStep::kBlockSize == b &&
        m.watch % ObservationEStep::kBlockSize < static_cast<int>(n)) {
      out.watch = static_cast<int>(out.trajectories) + m.watch % ObservationEStep::kBlockSize;
    }
    out.blocks.emplace_back(b, digest);
    out.trajectories += n;
  }
  return out;
}

// The held blocks' trajectories checked against the request's W symbols and 1 + E sources
// (before any is lent: a request that does not fit them must leave them as they were).
void check_blocks(const LocalBlocks& local, const std::map<std::uint64_t, std::vector<ObservedTrajectory>>& held, int W,
                  int E) {
  for (const auto& [b, digest] : local.blocks) {
    for (const auto& t : held.at(digest)) {
      for (int w : t.symbols) {
        if (w >= W) throw InputError("estep_request.num_symbols", "is smaller than the blocks' alphabet");
      }
      if (t.num_observations() > 0 && t.eta.cols() != 1 + E)
        throw InputError("estep_request.num_confounders", "does not fit the blocks' eta");
    }
  }
}

// The worker never refines alpha or eta: only the prior's shape matters here. With
// learned eta the trajectories carry the optimiser's contexts.
ObservationPrior worker_prior(int P, int W, int E, bool learned_eta, Eigen::Index end_rows, Eigen::Index end_symbols) {
  ObservationPrior prior;
  prior.end_alpha = Eigen::MatrixXd::Ones(end_rows, end_symbols);
  prior.learn_eta = learned_eta;
  prior.num_symbols = W;
  prior.num_confounders = E;
  prior.subject_alpha = Eigen::MatrixXd::Ones(P, W);
  prior.confounder_alpha = Eigen::MatrixXd::Ones(E, W);
  return prior;
}

// The request's observation model (W symbols), finite and >= 0.
ObservationModel request_model(const hbirl::estep_request_t& m, int W) {
  ObservationModel model;
  model.subject = eigen_rows(m.subject_o, W);
  model.confounders = eigen_rows(m.confounder_o, W);
  if (m.num_end_rows > 0) {
    model.end = eigen_rows(m.end_o, m.num_end_symbols);
    if (!model.end.allFinite() || (model.end.array() < 0).any())
      throw InputError("estep_request.end_o", "the end sensor's model must be finite and >= 0");
  }
  if (!model.subject.allFinite() || !model.confounders.allFinite() || (model.subject.array() < 0).any() ||
      (model.confounders.array() < 0).any()) {
    throw InputError("estep_request.subject_o", "the observation model must be finite and >= 0");
  }
  return model;
}

// The request's learned eta per context, for blocks with num_contexts contexts.
RowMatrix request_context_eta(const hbirl::estep_request_t& m, int num_contexts) {
  if (m.num_contexts < num_contexts) {
    throw InputError("estep_request.num_contexts", std::to_string(m.num_contexts) + ", the blocks have " +
                                                       std::to_string(num_contexts) + " contexts");
  }
  RowMatrix eta = eigen_rows<RowMatrix>(m.context_eta, m.num_sources);
  if (!eta.allFinite() || (eta.array() < 0).any())
    throw InputError("estep_request.context_eta", "must be finite and >= 0");
  return eta;
}

// The answer for one block (its statistics s, computed since `start`) to request m.
hbirl::estep_result_t block_result(const hbirl::estep_request_t& m, const EStepStatistics& s, int P, int block,
                                   std::uint64_t digest, const std::string& worker, bool lying,
                                   Clock::time_point start) {
  const int W = m.num_symbols, E = m.num_confounders;
  const bool learned_eta = m.num_contexts > 0;
  hbirl::estep_result_t r{};
  r.utime = m.utime;
  r.request_id = m.request_id;
  r.worker = worker;
  r.block_digest = static_cast<std::int64_t>(digest);
  r.block = block;
  r.num_pairs = P;
  r.counts = lcm_vector(s.counts);
  if (lying && !r.counts.empty()) r.counts[0] += 1.0;
  r.num_symbols = W;
  r.num_confounders = E;
  r.alpha_subject = lcm_rows(s.alpha_dot.subject);
  r.alpha_confounder = lcm_rows(s.alpha_dot.confounders);
  r.num_end_rows = static_cast<std::int32_t>(s.alpha_dot.end.rows());
  r.num_end_symbols = static_cast<std::int32_t>(s.alpha_dot.end.cols());
  r.alpha_end = lcm_rows(s.alpha_dot.end);
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
  return r;
}

}  // namespace

SamplerWorker::SamplerWorker(Bus& bus, std::string id, Counters& counters, std::int64_t max_dataset_bytes)
    : bus_(bus), id_(std::move(id)), counters_(counters), max_dataset_bytes_(max_dataset_bytes) {
  subs_.add(bus_, subscribe(
                      bus_, channels::kMdp, counters_,
                      [this](const hbirl::mdp_t& m, const Message& raw) {
                        bus_.sign_for_run(raw.run);  // a worker of any run answers each in its own
                        on_mdp(m);
                      },
                      10000));
  // A whole share may arrive between two handle() calls; only the newest requests matter.
  subs_.add(bus_, subscribe(
                      bus_, channels::trajectory_channel(id_), counters_,
                      [this](const hbirl::trajectory_t& m, const Message& raw) {
                        bus_.sign_for_run(raw.run);
                        on_trajectory(m, raw.size);
                      },
                      100000));
  // A worker of every run of a shared key that starts after an optimiser sent its MDP: it
  // answers the optimiser it hears (its heartbeats then reach it, and it sends the MDP).
  subs_.add(bus_, subscribe(
                      bus_, channels::kStatus, counters_,
                      [this](const hbirl::service_status_t& m, const Message& raw) {
                        if (m.service == "optimiser" && !mdp_ && request_run_ == 0) bus_.sign_for_run(raw.run);
                      },
                      100));
  subs_.add(bus_, subscribe(
                      bus_, channels::kEStepRequest, counters_,
                      [this](const hbirl::estep_request_t& m, const Message& raw) {
                        bus_.sign_for_run(raw.run);
                        on_request(m, raw.run);
                      },
                      8));
}

int SamplerWorker::handle(int timeout_ms) {
  if (Clock::now() >= next_status_) {
    publish_status();
    next_status_ = Clock::now() + std::chrono::seconds(1);
  }
  const int handled = bus_.handle(timeout_ms);
  if (!pending_.empty() && Clock::now() - last_trajectory_ > kQuietBeforeServing) {
    try {
      serve(false);
    } catch (const InputError& e) {  // a request that does not fit what arrived: counted, dropped
      counters_.bad(channels::kEStepRequest.name, e.what());
      pending_.clear();
    }
  }
  return handled;
}

void SamplerWorker::status_soon() {
  next_status_ = std::min(next_status_, std::max(Clock::now(), last_status_ + std::chrono::milliseconds(100)));
}

void SamplerWorker::publish_status(const std::string& state) {
  last_status_ = Clock::now();
  hbirl::service_status_t s{};
  s.utime = wall_utime();
  s.service = "sampler";
  s.id = id_;
  s.seq = ++status_seq_;
  s.state = !state.empty() ? state : mdp_ ? "running" : "starting";
  s.messages_in = counters_.messages_in;
  s.messages_out = counters_.messages_out;
  s.bad_messages = counters_.bad_messages;
  s.gaps = counters_.gaps;
  s.trajectories = trajectories_held_;
  s.dataset_digest = static_cast<std::int64_t>(last_dataset_digest_);
  s.numerics = static_cast<std::int64_t>(numerics_fingerprint());
  s.mdp_digest = static_cast<std::int64_t>(mdp_digest_.load());
  for (const auto& [digest, block] : held_) s.held_block.push_back(static_cast<std::int64_t>(digest));
  s.num_held_blocks = static_cast<std::int32_t>(s.held_block.size());
  s.detail = counters_.last_problem;
  s.authenticated = counters_.authenticated;
  s.restarts = counters_.restarts;
  publish(bus_, channels::kStatus, s, counters_);
  touch_alive_file();
}

void SamplerWorker::on_mdp(const hbirl::mdp_t& m) {
  if (static_cast<std::uint64_t>(m.mdp_digest) == mdp_digest_ && mdp_) return;  // have it already
  std::optional<Mdp> mdp = incoming_mdp_.add(m);
  if (!mdp) return;
  take_back_lent();  // it computes on the old MDP
  mdp_ = std::move(mdp);
  mdp_digest_ = static_cast<std::uint64_t>(m.mdp_digest);
  publish_status();  // tell the optimiser at once
}

void SamplerWorker::on_trajectory(const hbirl::trajectory_t& m, int bytes) {
  trajectory_bytes_ += bytes;
  if (m.worker != id_) return;  // another worker's whose id has the same channel tag
  if (m.block_size != ObservationEStep::kBlockSize) {
    throw InputError("trajectory.block_size", std::to_string(m.block_size) + ", this worker's blocks have " +
                                                  std::to_string(ObservationEStep::kBlockSize));
  }
  if (m.num_trajectories < 1 || m.index < 0 || m.index >= m.num_trajectories) {
    throw InputError("trajectory.index",
                     std::to_string(m.index) + " is not in [0, " + std::to_string(m.num_trajectories) + ")");
  }
  last_trajectory_ = Clock::now();  // (after the checks: junk must not hold up serve())
  const auto digest = static_cast<std::uint64_t>(m.block_digest);
  if (held_.count(digest)) return;  // have it already
  const int block = m.index / m.block_size;
  const int size = std::min(m.block_size, m.num_trajectories - block * m.block_size);
  if (!incoming_.count(digest) &&
      incoming_.size() >= kMaxIncomingBlocks) {  // made-up digests: forget one (the smallest digest)
    release(incoming_.begin()->first);
    incoming_.erase(incoming_.begin());
  }
  Incoming& in = incoming_[digest];
  if (in.size == 0) in.size = size;
  if (in.size != size)
    throw InputError("trajectory.num_trajectories",
                     "puts its block at another size than the block's other trajectories");
  const int position = m.index - block * m.block_size;
  if (in.trajectories.count(position)) return;  // a repeat
  const std::int64_t need = held_bytes(m);
  if (bytes_ + need > max_dataset_bytes_) drop_unassigned(false);
  if (bytes_ + need > max_dataset_bytes_) {
    release(digest);
    incoming_.erase(digest);
    status_soon();
    throw InputError("trajectory", "the blocks would take more than --max-dataset-mb " +
                                       std::to_string(max_dataset_bytes_ >> 20) + " MB: this block is dropped");
  }
  in.trajectories.emplace(position, from_message(m));
  bytes_ += need;
  block_bytes_[digest] += need;
  if (static_cast<int>(in.trajectories.size()) < in.size) return;
  std::vector<ObservedTrajectory> all;
  all.reserve(in.trajectories.size());
  for (auto& [index, t] : in.trajectories) all.push_back(std::move(t));
  incoming_.erase(digest);
  if (dataset_digest(all) != digest) {
    release(digest);
    status_soon();
    throw InputError("trajectory.block_digest", "does not match the block's trajectories received");
  }
  held_.emplace(digest, std::move(all));
  held_changed();
  serve(true);
  if (incoming_.empty()) publish_status();  // tell the optimiser at once what it holds
}

void SamplerWorker::held_changed() {
  int n = 0;
  for (const auto& [digest, block] : held_) n += static_cast<int>(held_size(digest));
  trajectories_held_ = n;
}

// The blocks no longer assigned to it (they went to other workers) are dropped: those held
// and, with `incoming_too`, those partly received (not when memory runs short: a block is
// sent before the request that assigns it, and made-up blocks must not push it out).
void SamplerWorker::drop_unassigned(bool incoming_too) {
  std::set<std::uint64_t> keep;
  for (const auto& [block, digest] : assigned_) keep.insert(digest);
  const auto drop_from = [&](auto& blocks) {
    bool dropped = false;
    for (auto it = blocks.begin(); it != blocks.end();) {
      if (keep.count(it->first)) {
        ++it;
        continue;
      }
      release(it->first);
      it = blocks.erase(it);
      dropped = true;
    }
    return dropped;
  };
  if (incoming_too) drop_from(incoming_);
  // A block the E-step holds is taken back first, to go with the rest.
  if (std::any_of(lent_.begin(), lent_.end(), [&](const auto& x) { return !keep.count(x.first); })) take_back_lent();
  if (drop_from(held_)) held_changed();
}

size_t SamplerWorker::held_size(std::uint64_t digest) const {
  const auto lent = lent_.find(digest);
  if (lent != lent_.end()) return lent->second;
  const auto it = held_.find(digest);
  return it == held_.end() ? 0 : it->second.size();
}

// The listed held blocks' trajectories in order, moved out of held_ (a block listed twice
// -- two blocks of the same content -- is copied for its second place).
std::vector<ObservedTrajectory> SamplerWorker::gather(const std::vector<std::pair<int, std::uint64_t>>& blocks,
                                                      size_t trajectories) {
  std::vector<ObservedTrajectory> data;
  data.reserve(trajectories);  // moving in allocates nothing: only a second place's copy can fail
  std::map<std::uint64_t, std::pair<size_t, size_t>> placed;  // digest -> (first index, size)
  try {
    for (const auto& [b, digest] : blocks) {
      const auto seen = placed.find(digest);
      if (seen != placed.end()) {
        const auto [first, n] = seen->second;
        for (size_t i = 0; i < n; ++i) data.push_back(data[first + i]);
        continue;
      }
      std::vector<ObservedTrajectory>& block = held_.at(digest);
      placed[digest] = {data.size(), block.size()};
      lent_[digest] = block.size();
      for (auto& t : block) data.push_back(std::move(t));
      block = {};  // its place in held_ stays: the block is held, by the E-step
    }
  } catch (...) {  // out of memory copying a second place: what was moved goes back
    give_back(std::move(data), blocks);
    throw;
  }
  return data;
}

// What gather() took, back into held_ in the same order (the E-step's trajectories are
// the blocks merged, which the optimiser's already are: merging again changes nothing).
void SamplerWorker::give_back(std::vector<ObservedTrajectory>&& data,
                              const std::vector<std::pair<int, std::uint64_t>>& blocks) {
  size_t at = 0;
  for (const auto& [b, digest] : blocks) {
    std::vector<ObservedTrajectory>& block = held_.at(digest);
    const auto lent = lent_.find(digest);
    if (lent == lent_.end()) {  // its second place, a copy: given back already
      at += block.size();
      continue;
    }
    block.reserve(lent->second);
    for (size_t i = 0; i < lent->second; ++i) block.push_back(std::move(data[at + i]));
    at += lent->second;
    lent_.erase(lent);
  }
}

// The blocks the E-step holds, back into held_; the E-step goes.
void SamplerWorker::take_back_lent() {
  if (!estep_) return;
  std::vector<ObservedTrajectory> data = std::move(*estep_).take_trajectories();
  estep_.reset();
  give_back(std::move(data), estep_blocks_);
  estep_blocks_.clear();
}

// The memory a block took is free again.
void SamplerWorker::release(std::uint64_t digest) {
  const auto it = block_bytes_.find(digest);
  if (it == block_bytes_.end()) return;
  bytes_ -= it->second;
  block_bytes_.erase(it);
}

void SamplerWorker::check_request(const hbirl::estep_request_t& m) const {
  const int P = mdp_->num_pairs(), W = m.num_symbols, E = m.num_confounders;
  if (m.engine != "exact")
    throw InputError("estep_request.engine", "'" + m.engine + "' is not an engine this worker has");
  if (m.num_pairs != P) throw InputError("estep_request.num_pairs", "is not the MDP's |S||A| = " + std::to_string(P));
  if (m.block_size != ObservationEStep::kBlockSize)
    throw InputError("estep_request.block_size", "differs from this worker's");
  if (m.num_trajectories < 1 || m.num_blocks != (m.num_trajectories + m.block_size - 1) / m.block_size) {
    throw InputError("estep_request.num_blocks", "is not the number of blocks of num_trajectories");
  }
  if (W < 1 || E < 0) throw InputError("estep_request.num_symbols", "must be >= 1 (and num_confounders >= 0)");
  if (m.watch < -1 || m.watch >= m.num_trajectories)
    throw InputError("estep_request.watch", "is not a trajectory of the data set");
  if (m.num_contexts < 0) throw InputError("estep_request.num_contexts", "is negative");
  if (m.num_contexts > 0 && (E < 1 || m.num_sources != 1 + E)) {
    throw InputError("estep_request.num_sources", "learned eta needs 1 + num_confounders sources and a confounder");
  }
}

void SamplerWorker::on_request(const hbirl::estep_request_t& m, std::uint64_t run) {
  if (!answered_.insert({m.request_id, m.attempt}).second) return;  // a repeat: answered already
  while (answered_.size() > 256) answered_.erase(answered_.begin());
  if (static_cast<std::uint64_t>(m.mdp_digest) != mdp_digest_ || !mdp_) {
    publish_status();  // the optimiser sees our digest and sends its MDP
    return;
  }
  std::vector<int> mine;
  for (int b = 0; b < m.num_blocks; ++b) {
    if (m.assigned_worker[static_cast<size_t>(b)] == id_) mine.push_back(b);
  }
  if (!mine.empty()) check_request(m);
  if (!request_ || request_->request_id != m.request_id) {  // another pass: what the last one asked is over
    pending_.clear();
    request_.reset();
    // Its blocks are this pass's only: never a mix of two passes' (two optimisers, a forger).
    assigned_.clear();
  } else if (m.num_blocks != request_->num_blocks || m.block_digest != request_->block_digest) {
    throw InputError("estep_request.block_digest", "differs from an earlier attempt of the same request");
  }
  for (int b : mine) assigned_[b] = static_cast<std::uint64_t>(m.block_digest[static_cast<size_t>(b)]);
  if (m.attempt == 0) drop_unassigned(true);  // its share of this pass: what it holds beyond went to other workers
  if (mine.empty()) return;
  last_dataset_digest_ = static_cast<std::uint64_t>(m.dataset_digest);
  request_ = m;
  request_run_ = run;
  pending_.insert(mine.begin(), mine.end());
  serve(true);
}

void SamplerWorker::serve(bool all_here_only) {
  if (!request_ || pending_.empty()) return;
  const hbirl::estep_request_t& m = *request_;
  bus_.sign_for_run(request_run_);  // the answers are the request's run's
  std::vector<int> ready;
  for (int b : pending_) {
    if (held_.count(static_cast<std::uint64_t>(m.block_digest[static_cast<size_t>(b)]))) ready.push_back(b);
  }
  if (ready.empty() || (all_here_only && ready.size() < pending_.size())) return;
  const int P = mdp_->num_pairs(), W = m.num_symbols, E = m.num_confounders;
  const bool learned_eta = m.num_contexts > 0;
  const LocalBlocks local = local_blocks(m, assigned_, [this](std::uint64_t d) { return held_size(d); });
  const std::vector<std::pair<int, std::uint64_t>>& blocks = local.blocks;
  const auto shape = std::make_tuple(W, E, m.max_kinds, static_cast<bool>(m.kind_table), local.watch, learned_eta,
                                     m.num_end_rows, m.num_end_symbols);
  if (!estep_ || blocks != estep_blocks_ || shape != estep_shape_) {
    take_back_lent();
    check_blocks(local, held_, W, E);
    ObservationEStepOptions options;
    options.max_kinds = m.max_kinds;
    options.kind_table = static_cast<bool>(m.kind_table);
    options.watch = local.watch;
    // The E-step takes the blocks over (merged in place: merging the optimiser's merged
    // trajectories again changes nothing), so each is held once.
    std::vector<ObservedTrajectory> data = gather(blocks, local.trajectories);
    try {
      estep_.emplace(*mdp_, std::move(data), worker_prior(P, W, E, learned_eta, m.num_end_rows, m.num_end_symbols),
                     options);
    } catch (...) {
      // Refused before it took them (a request that does not fit): nothing accepted is lost.
      if (data.size() == local.trajectories) {
        give_back(std::move(data), blocks);
      } else {  // out of memory while taking them over: they are gone
        for (const auto& [digest, size] : lent_) {
          release(digest);
          held_.erase(digest);
        }
        lent_.clear();
        held_changed();
      }
      throw;
    }
    estep_blocks_ = blocks;
    estep_shape_ = shape;
  }
  SoftSolution policy;
  policy.log_policy = eigen_vector(m.log_policy);
  policy.policy = eigen_vector(m.policy);
  const ObservationModel model = request_model(m, W);
  std::optional<RowMatrix> eta;
  if (learned_eta) eta = request_context_eta(m, estep_->num_contexts());
  // One block at a time, each answer sent as soon as it is ready.
  for (const int block : ready) {
    pending_.erase(block);
    const auto local_block =
        std::find_if(blocks.begin(), blocks.end(), [block](const auto& x) { return x.first == block; });
    const auto start = Clock::now();
    const EStepStatistics s =
        estep_
            ->block_statistics(policy, model, static_cast<std::uint64_t>(m.seed),
                               {static_cast<int>(local_block - blocks.begin())}, 1, eta ? &*eta : nullptr)
            .front();
    publish(bus_, channels::kEStepResult, block_result(m, s, P, block, local_block->second, id_, lying_, start),
            counters_);
    ++blocks_computed_;
  }
}

}  // namespace hbirl::services
