// The optimiser's side of the E-step over the bus: the pass (estep_service.hpp).
#include "services/estep_service.hpp"

#include <algorithm>
#include <random>
#include <stdexcept>

#include "learner/digest.hpp"
#include "learner/input_error.hpp"
#include "services/block_placement.hpp"

namespace hbirl::services {

namespace {

using Clock = std::chrono::steady_clock;

// Request ids: random, so that two optimisers on one bus never take each other's answers.
std::int64_t random_request_id() {
  std::random_device entropy;
  return static_cast<std::int64_t>((static_cast<std::uint64_t>(entropy()) << 32 | entropy()) >> 1);
}

}  // namespace

std::vector<int> BusBlockExecutor::Pass::missing() const {
  std::vector<int> out;
  for (int b = 0; b < static_cast<int>(received.size()); ++b) {
    if (!received[static_cast<size_t>(b)]) out.push_back(b);
  }
  return out;
}

BusBlockExecutor::BusBlockExecutor(Bus& bus, const Mdp& mdp, const std::string& domain, Counters& counters,
                                   BusExecutorOptions options)
    : bus_(bus),
      mdp_messages_(to_messages(mdp, domain)),
      mdp_digest_(dynamics_digest(mdp)),
      counters_(counters),
      options_(options),
      roster_(mdp_digest_, numerics_fingerprint(), options.same_numerics_only, options.worker_silence_s),
      window_(bus, counters, options.send_window_bytes, std::chrono::milliseconds(options.timeout_ms)),
      request_id_(random_request_id()) {
  subs_.add(bus_, subscribe(
                      bus_, channels::kStatus, counters_,
                      [this](const hbirl::service_status_t& m, const Message&) { on_status(m); }, 1000));
  // Every block of a pass may arrive between two handle() calls.
  subs_.add(bus_, subscribe(
                      bus_, channels::kEStepResult, counters_,
                      [this](const hbirl::estep_result_t& m, const Message&) { on_result(m); }, 100000));
}

void BusBlockExecutor::publish_mdp() {
  last_mdp_sent_ = Clock::now();
  for (const auto& m : mdp_messages_) publish(bus_, channels::kMdp, m, counters_);
}

void BusBlockExecutor::prepare_blocks(const ObservationEStep& estep) {
  if (blocks_.estep == &estep && blocks_.input == estep.input_digest() && blocks_.contexts == estep.num_contexts() &&
      blocks_.kinds == estep.uses_kind_table()) {
    return;
  }
  blocks_.estep = &estep;
  blocks_.input = estep.input_digest();
  blocks_.contexts = estep.num_contexts();
  blocks_.kinds = estep.uses_kind_table();
  blocks_.digests.clear();
  for (int b = 0; b < estep.num_blocks(); ++b)
    blocks_.digests.push_back(dataset_digest(block_of(estep.trajectories(), b)));
  blocks_.current = std::set<std::uint64_t>(blocks_.digests.begin(), blocks_.digests.end());
  blocks_.data_digest = dataset_digest(estep.trajectories());
  blocks_.exact = estep.options().engine.exact;
  if (owners_.size() != blocks_.digests.size()) owners_.assign(blocks_.digests.size(), std::string());
  roster_.new_data_set();
}

void BusBlockExecutor::on_status(const hbirl::service_status_t& m) {
  const WorkerRoster::Heard heard = roster_.hear(m, blocks_.current);
  progress_ += heard.acknowledged;
  if (heard.new_numerics) {
    ++stats_.other_numerics;
    counters_.note("sampler " + m.id + " computes with other numerics (fingerprint " +
                   std::to_string(static_cast<std::uint64_t>(m.numerics)) + ", here " +
                   std::to_string(roster_.numerics()) + ")" +
                   (options_.same_numerics_only ? ": it gets no work"
                                                : ": theta may differ from a one-process run in the last bits"));
  }
  // A worker without our MDP: send it (not more than twice a second). Its blocks are sent
  // with the pass that gives them to it.
  if (heard.needs_mdp && Clock::now() - last_mdp_sent_ > std::chrono::milliseconds(500)) publish_mdp();
}

// An answer: believed only when it is of this pass, of its data, from the worker the block
// was given to, not distrusted, and statistics of the request's shape (estep_wire.hpp).
void BusBlockExecutor::on_result(const hbirl::estep_result_t& m) {
  if (m.request_id != request_id_ || pass_.received.empty()) {
    ++stats_.stale;
    return;
  }
  if (m.block < 0 || m.block >= pass_.shape.blocks)
    throw InputError("estep_result.block", std::to_string(m.block) + " is not a block");
  if (static_cast<std::uint64_t>(m.block_digest) !=
      blocks_.digests[static_cast<size_t>(m.block)]) {  // computed on other trajectories
    ++stats_.foreign;
    return;
  }
  check_shape(m, pass_.shape);
  const auto& slot = pass_.received[static_cast<size_t>(m.block)];
  if (slot &&
      pass_.answered_by[static_cast<size_t>(m.block)] != m.worker) {  // answered already, by the worker it was given to
    ++stats_.duplicates;
    return;
  }
  if (m.worker.empty()) throw InputError("estep_result.worker", "is empty");
  if (!pass_.assigned[static_cast<size_t>(m.block)].count(m.worker)) {  // only the worker given the block is believed
    ++stats_.unassigned;
    throw InputError("estep_result.worker", "'" + m.worker + "' was not given block " + std::to_string(m.block));
  }
  if (roster_[m.worker].distrusted || pass_.doubted.count(m.worker)) {
    throw InputError("estep_result.worker", "'" + m.worker + "' answered wrong: its answers are not used");
  }
  take_answer(m, statistics_of(m, pass_.shape));
}

void BusBlockExecutor::take_answer(const hbirl::estep_result_t& m, EStepStatistics s) {
  auto& slot = pass_.received[static_cast<size_t>(m.block)];
  if (slot) {
    // A worker computes a block's bits the same way every time: two different answers
    // under one name mean one is forged (without a run key anyone can use any name), and
    // nothing says which. The blocks answered under that name are computed here this
    // pass; the name keeps its work (a forger must not be able to bench a worker).
    if (!same_statistics(*slot, s, 0.0)) {
      ++stats_.conflicts;
      pass_.doubted.insert(m.worker);
      counters_.bad(channels::kEStepResult.name, "two different answers to block " + std::to_string(m.block) +
                                                     " under the name '" + m.worker +
                                                     "' (one forged?): its blocks of this pass are computed here");
      forget_answers_of(m.worker);
      return;
    }
    ++stats_.duplicates;
    return;
  }
  slot = std::move(s);
  ++progress_;
  pass_.answered.insert(m.worker);
  pass_.answered_by[static_cast<size_t>(m.block)] = m.worker;
  Worker& w = roster_[m.worker];
  w.suspect = false;  // it does answer
  w.ever_answered = true;
  ++w.answers;
  ++stats_.remote_blocks;
  ++stats_.blocks_by_worker[m.worker];
}

int BusBlockExecutor::wait_for_workers(int count, int timeout_ms) {
  const std::lock_guard<std::recursive_mutex> lock(mutex_);
  publish_mdp();
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  const auto live = [this] { return static_cast<int>(roster_.live(stats_.trial_passes < kMaxTrialPasses).size()); };
  while (live() < count && Clock::now() < deadline) {
    if (options_.stop && options_.stop()) break;
    if (options_.idle) options_.idle();
    if (bus_.handle(20) < 0) break;
  }
  return live();
}

// A worker caught answering wrong: no more work, no more of its answers, and every block
// it answered in this pass is computed again.
void BusBlockExecutor::distrust(const std::string& worker, const std::string& why) {
  ++stats_.liars;
  roster_[worker].distrusted = true;
  counters_.bad(
      channels::kEStepResult.name,
      "worker '" + worker + "' " + why + ": it gets no more work, and its blocks of this pass are computed here");
  forget_answers_of(worker);
}

// The blocks `worker` answered in this pass are missing again (computed here, or by
// another worker in a later attempt).
void BusBlockExecutor::forget_answers_of(const std::string& worker) {
  for (size_t b = 0; b < pass_.answered_by.size(); ++b) {
    if (pass_.answered_by[b] != worker) continue;
    pass_.received[b].reset();
    pass_.answered_by[b].clear();
    --stats_.remote_blocks;
    if (--stats_.blocks_by_worker[worker] <= 0) stats_.blocks_by_worker.erase(worker);
  }
}

BusBlockExecutor::Stats BusBlockExecutor::stats() const {
  const std::lock_guard<std::recursive_mutex> lock(mutex_);
  Stats out = stats_;
  out.trajectories_sent = window_.trajectories_sent();
  out.bytes_sent = window_.bytes_sent();
  return out;
}

int BusBlockExecutor::pump(const ObservationEStep& estep) {
  const int sent = window_.pump(estep, blocks_.digests, roster_);
  progress_ += sent;  // sending goes on: the pass is not stuck
  return sent;
}

// Every block here: learned eta with more contexts than a request carries (a sensor
// without contexts whose every eta differs has about one context per observation: each
// pass would send them all to every worker).
std::vector<EStepStatistics> BusBlockExecutor::compute_here(const ObservationEStep& estep, const SoftSolution& policy,
                                                            const ObservationModel& model, std::uint64_t seed,
                                                            const RowMatrix* eta) {
  if (!said_too_many_contexts_) {
    counters_.note("learned eta has " + std::to_string(eta->rows()) +
                   " contexts (each distinct eta is one), more than the " + std::to_string(options_.max_contexts) +
                   " a request carries: the E-step is computed here, not by the workers "
                   "(give the observations contexts, or --eta stated)");
    said_too_many_contexts_ = true;
  }
  std::vector<int> all(static_cast<size_t>(estep.num_blocks()));
  for (int b = 0; b < estep.num_blocks(); ++b) all[static_cast<size_t>(b)] = b;
  stats_.local_blocks += estep.num_blocks();
  return estep.block_statistics(policy, model, seed, all, options_.local_threads, eta);
}

// First attempt: every live worker whose answers are not doubted. Later ones: those of
// them that answered this request (if any did).
std::vector<std::string> BusBlockExecutor::workers_for(int attempt) {
  std::vector<std::string> workers = roster_.live(stats_.trial_passes < kMaxTrialPasses);
  std::erase_if(workers, [this](const std::string& w) { return pass_.doubted.count(w) > 0; });
  if (attempt == 0) return workers;
  std::vector<std::string> proven;
  for (const auto& w : workers) {
    if (pass_.answered.count(w)) proven.push_back(w);
  }
  return proven.empty() ? workers : proven;
}

// Handles the bus until every block is answered, or only refused workers' are missing, or
// a timeout passes without progress (an answer, a block acknowledged): a worker still
// receiving its share or computing a long block is not re-asked.
void BusBlockExecutor::wait_for_answers(const ObservationEStep& estep, const std::vector<std::string>& assigned) {
  auto deadline = Clock::now() + std::chrono::milliseconds(options_.timeout_ms);
  std::int64_t seen = progress_;
  const auto awaited = [&] {
    for (int b : pass_.missing()) {
      const std::string& w = assigned[static_cast<size_t>(b)];
      if (!w.empty() && !pass_.doubted.count(w) && !roster_[w].distrusted) return true;
    }
    return false;
  };
  while (!pass_.missing().empty() && awaited() && Clock::now() < deadline) {
    if (options_.stop && options_.stop()) throw Stopped();
    if (options_.idle) options_.idle();
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    if (bus_.handle(static_cast<int>(std::clamp<long long>(left, 0, 50))) < 0) break;
    pump(estep);
    if (progress_ != seen) {
      seen = progress_;
      deadline = Clock::now() + std::chrono::milliseconds(options_.timeout_ms);
    }
  }
}

// After an attempt: what the workers that left blocks unanswered are told. Workers with
// blocks still queued were not given the chance to answer: not their fault.
void BusBlockExecutor::judge_silence(const std::vector<std::string>& assigned) {
  bool trial_failed = false;
  const std::set<std::string> queued = window_.drop();  // what is still queued goes with the next attempt
  for (int b : pass_.missing()) {
    const std::string& w = assigned[static_cast<size_t>(b)];
    if (w.empty() || queued.count(w)) continue;
    // Sent, and a heartbeat since that says it is not held: counted; twice, and the block
    // goes to others. (A worker busy computing sends no heartbeat: no strike. A name whose
    // answers are doubted is not judged by what may be a forger's heartbeats.)
    Worker& x = roster_[w];
    const std::uint64_t digest = blocks_.digests[static_cast<size_t>(b)];
    const auto sent = x.sent.find(digest);
    if (sent != x.sent.end() && x.last_seen > sent->second.when && !x.held.count(digest) && !pass_.doubted.count(w) &&
        !x.distrusted) {
      x.last_unheld = Clock::now();
      ++x.unheld[digest];
    }
    // Workers that left blocks unanswered get no more work until they are heard from again
    // (a worker that missed a request works again). A pass that waited on one that never
    // answered at all counts against the run's budget of such passes: made-up workers,
    // whatever their number and the rate of their heartbeats, cost at most
    // kMaxTrialPasses timeouts in all.
    if (pass_.answered.count(w)) continue;
    trial_failed = trial_failed || !x.ever_answered;
    x.suspect_now();
  }
  stats_.trial_passes += trial_failed;
}

// The spot-checked blocks, computed here during the first attempt: an answer that differs
// gets its worker distrusted; a block not answered takes the result computed here. A worker
// never checked that left its checked block to someone else has none of its answers of this
// pass checked: none is used.
void BusBlockExecutor::check_spots(const std::vector<int>& spots, std::vector<EStepStatistics>& here,
                                   const std::vector<std::string>& given) {
  for (size_t k = 0; k < spots.size(); ++k) {
    const int block = spots[k];
    auto& slot = pass_.received[static_cast<size_t>(block)];
    if (!slot) {
      slot = std::move(here[k]);  // not answered: computed here already
      ++stats_.local_blocks;
    } else {
      const std::string worker = pass_.answered_by[static_cast<size_t>(block)];
      if (!spot_checks_.matches(worker, *slot, here[k], roster_)) {
        distrust(worker, "answered block " + std::to_string(block) + " unlike the optimiser's own computation");
        pass_.received[static_cast<size_t>(block)] = here[k];
        ++stats_.local_blocks;
      }
    }
    const Worker* meant = roster_.find(given[k]);
    if (meant != nullptr && !meant->checked && !meant->distrusted) forget_answers_of(given[k]);
  }
}

std::vector<EStepStatistics> BusBlockExecutor::run(const ObservationEStep& estep, const SoftSolution& policy,
                                                   const ObservationModel& model, std::uint64_t seed,
                                                   const RowMatrix* eta) {
  const std::lock_guard<std::recursive_mutex> lock(mutex_);
  if (options_.stop && options_.stop()) throw Stopped();
  const auto start = Clock::now();
  // First what came while the optimiser was busy elsewhere (heartbeats above all: who is
  // live is decided from them). Bounded, so a flood cannot hold the pass up.
  for (int k = 0; k < 100000 && bus_.handle(0) > 0; ++k) {
  }
  // The workers compute with the exact engine on this executor's MDP: the pass must too.
  if (dynamics_digest(estep.mdp()) != mdp_digest_)
    throw std::logic_error("BusBlockExecutor: the E-step's MDP is not the workers'");
  prepare_blocks(estep);
  if (!blocks_.exact) throw std::logic_error("BusBlockExecutor: workers run the exact engine only");
  ++request_id_;
  ++stats_.requests;
  if (eta && (eta->rows() != estep.num_contexts() || eta->cols() != 1 + model.num_confounders())) {
    throw std::logic_error("BusBlockExecutor: learned eta does not have one row per context and a column per source");
  }
  if (eta && eta->rows() > options_.max_contexts) return compute_here(estep, policy, model, seed, eta);
  const int blocks = estep.num_blocks();
  pass_ = Pass{};
  pass_.shape = ResultShape{};
  pass_.shape.blocks = blocks;
  pass_.shape.pairs = estep.mdp().num_pairs();
  pass_.shape.symbols = model.num_symbols();
  pass_.shape.confounders = model.num_confounders();
  pass_.shape.contexts = eta ? static_cast<int>(eta->rows()) : 0;
  pass_.shape.watch = estep.options().watch;
  pass_.shape.end_rows = static_cast<int>(model.end.rows());
  pass_.shape.end_symbols = static_cast<int>(model.end.cols());
  pass_.shape.end_reported.assign(static_cast<size_t>(blocks), 0);
  for (size_t i = 0; i < estep.trajectories().size(); ++i) {
    if (!estep.trajectories()[i].end_symbols.empty()) pass_.shape.end_reported[i / ObservationEStep::kBlockSize] = 1;
  }
  if (pass_.shape.watch >= 0)
    pass_.shape.watch_steps = estep.trajectories()[static_cast<size_t>(pass_.shape.watch)].length();
  pass_.received.assign(static_cast<size_t>(blocks), std::nullopt);
  pass_.assigned.assign(static_cast<size_t>(blocks), {});
  pass_.answered_by.assign(static_cast<size_t>(blocks), std::string());
  std::vector<int> spots;  // the blocks checked here this pass, their statistics, and whom each was given to
  std::vector<EStepStatistics> spot_results;
  std::vector<std::string> spot_workers;

  hbirl::estep_request_t request = request_message(
      {request_id_, blocks_.data_digest, mdp_digest_, &blocks_.digests, seed}, estep, policy, model, eta);
  for (int attempt = 0; attempt < options_.max_attempts; ++attempt) {
    const std::vector<int> todo = pass_.missing();
    if (todo.empty()) break;
    const std::vector<std::string> workers = workers_for(attempt);
    if (workers.empty()) break;
    if (attempt > 0) stats_.retried_blocks += static_cast<std::int64_t>(todo.size());
    ++stats_.attempts;
    request.attempt = attempt;
    request.assigned_worker = place_blocks(todo, workers, blocks_.digests, owners_, roster_);
    for (int b : todo) {  // a block given to nobody (none can hold it) is computed here: no answer to it is believed
      const std::string& w = request.assigned_worker[static_cast<size_t>(b)];
      if (!w.empty()) pass_.assigned[static_cast<size_t>(b)].insert(w);
    }
    window_.queue(todo, request.assigned_worker, blocks_.digests, roster_);
    pump(estep);
    publish(bus_, channels::kEStepRequest, request, counters_);
    if (attempt == 0 && options_.spot_check) {  // computed here while the workers compute the rest
      spots = spot_checks_.choose(todo, request.assigned_worker, roster_);
      for (int b : spots) spot_workers.push_back(request.assigned_worker[static_cast<size_t>(b)]);
      spot_results = estep.block_statistics(policy, model, seed, spots, options_.local_threads, eta);
      stats_.spot_checks += static_cast<std::int64_t>(spots.size());
    }
    wait_for_answers(estep, request.assigned_worker);
    judge_silence(request.assigned_worker);
  }
  check_spots(spots, spot_results, spot_workers);
  const std::vector<int> rest = pass_.missing();
  if (!rest.empty()) {
    const std::vector<EStepStatistics> local =
        estep.block_statistics(policy, model, seed, rest, options_.local_threads, eta);
    for (size_t k = 0; k < rest.size(); ++k) pass_.received[static_cast<size_t>(rest[k])] = local[k];
    stats_.local_blocks += static_cast<std::int64_t>(rest.size());
  }
  std::vector<EStepStatistics> out;
  out.reserve(pass_.received.size());
  for (auto& s : pass_.received) out.push_back(std::move(*s));
  pass_.received.clear();  // answers from now on are stale
  stats_.round_trip_s += std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

}  // namespace hbirl::services
