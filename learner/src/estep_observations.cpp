#include "learner/estep_observations.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "learner/input_error.hpp"
#include "learner/parallel.hpp"

namespace hbirl {

EngineFactory exact_engine_factory() {
  return {[](const Mdp& mdp) -> std::unique_ptr<PosteriorEngine> { return std::make_unique<ExactEngine>(mdp); }, true};
}

ObservationEStep::ObservationEStep(const Mdp& mdp, const std::vector<ObservedTrajectory>& trajectories,
                                   ObservationPrior prior, ObservationEStepOptions options)
    : mdp_(mdp), prior_(std::move(prior)), options_(std::move(options)) {
  check_data(trajectories);
  trajectories_.reserve(trajectories.size());
  for (const auto& t : trajectories) trajectories_.push_back(merge_identical_observations(t));
  finish();
}

ObservationEStep::ObservationEStep(const Mdp& mdp, std::vector<ObservedTrajectory>&& trajectories,
                                   ObservationPrior prior, ObservationEStepOptions options)
    : mdp_(mdp), prior_(std::move(prior)), options_(std::move(options)) {
  check_data(trajectories);  // refused: they are the caller's still
  trajectories_ = std::move(trajectories);
  for (auto& t : trajectories_) t = merge_identical_observations(t);  // one trajectory's copy at a time
  finish();
}

// Whatever refuses the data is checked on them as given, before any is merged or taken
// over: merging changes none of it.
void ObservationEStep::check_data(const std::vector<ObservedTrajectory>& trajectories) const {
  const Mdp& mdp = mdp_;
  if (trajectories.empty()) throw InputError("demonstration", "no trajectories with observations");
  if (options_.cross_fit && options_.executor)
    throw InputError("cross_fit", "cross-fitted passes are computed here, not by an executor");
  if (options_.watch < -1 || options_.watch >= static_cast<int>(trajectories.size())) {
    throw InputError("watch", std::to_string(options_.watch) + " is not a trajectory of the data");
  }
  if (prior_.subject_alpha.rows() != mdp.num_pairs() || prior_.subject_alpha.cols() != prior_.num_symbols ||
      prior_.confounder_alpha.rows() != prior_.num_confounders ||
      prior_.confounder_alpha.cols() != prior_.num_symbols) {
    throw InputError("observation_model", "alpha has the wrong shape");
  }
  if (prior_.end_alpha.size() > 0 && prior_.end_alpha.rows() != mdp.num_states)
    throw InputError("end_alpha", "has " + std::to_string(prior_.end_alpha.rows()) + " rows, expected one per state (" +
                                      std::to_string(mdp.num_states) + ")");
  for (size_t i = 0; i < trajectories.size(); ++i) {
    const ObservedTrajectory& t = trajectories[i];
    if (t.length() < 1) throw InputError("demonstration[" + std::to_string(i) + "].steps", "is empty");
    if (t.num_observations() > 0 && t.eta.cols() != 1 + prior_.num_confounders) {
      throw InputError("demonstration[" + std::to_string(i) + "].steps", "eta has the wrong number of sources");
    }
    if (t.end_state >= 0 && (!t.ends_in_terminal || t.end_state >= mdp.num_states || !mdp.is_terminal(t.end_state))) {
      throw InputError("demonstration[" + std::to_string(i) + "].end_state",
                       std::to_string(t.end_state) + " is not a terminal state the trajectory ended in");
    }
    try {
      end_log_evidence(mdp, t, prior_.end_alpha);
    } catch (const InputError& e) {
      throw InputError("demonstration[" + std::to_string(i) + "]." + e.field(), e.message());
    }
  }
  if (!learns_eta()) return;
  if (!(prior_.eta_strength > 0.0)) throw InputError("observation_model.eta_prior_strength", "must be positive");
  // Explicit contexts (assign_contexts): every observation has one, or none has.
  const bool given = std::any_of(trajectories.begin(), trajectories.end(),
                                 [](const ObservedTrajectory& t) { return !t.contexts.empty(); });
  if (!given) return;
  for (const auto& t : trajectories) {
    if (t.num_observations() > 0 && t.contexts.size() != static_cast<size_t>(t.num_observations())) {
      throw InputError("demonstration", "some observations have a context and others not");
    }
    for (int c : t.contexts) {
      if (c < 0 || c >= kMaxContexts) {
        throw InputError("demonstration",
                         "context " + std::to_string(c) + " is outside [0, " + std::to_string(kMaxContexts - 1) + "]");
      }
    }
  }
}

// What the merged trajectories are read for: the executor's digest, learned eta's
// contexts and the kind table (nothing here refuses what check_data accepted).
void ObservationEStep::finish() {
  // The tie reads the controlled run's counts only, so every E-step built from one prior
  // (restarts, the optimiser, anytime learning) ties it alike; with O held (learn false:
  // the confidence's second opinion) the held O is the tied prior's mean (initial_state).
  if (ties_subject_prior(prior_)) tie_subject_prior_across_actions(prior_, mdp_.num_actions);
  if (options_.executor) {
    input_digest_ = dataset_digest(trajectories_);
  }
  if (learns_eta()) assign_contexts();
  long long rows = 0;
  for (const auto& t : trajectories_) rows += t.num_observations();
  if (options_.max_kinds > 0 && options_.kind_table.value_or(true)) {
    kinds_ = observation_kinds(trajectories_, options_.max_kinds);
    if (kinds_ && !options_.kind_table && 4LL * kinds_->num_kinds() > rows) kinds_.reset();
  }
}

std::vector<ObservedTrajectory> ObservationEStep::take_trajectories() && {
  if (numbered_contexts_) {
    for (auto& t : trajectories_) t.contexts.clear();
  }
  return std::move(trajectories_);
}

void ObservationEStep::assign_contexts() {
  // Explicit contexts are numbered from 0 (check_data has checked them); without them each
  // distinct eta is one. A context's stated eta is the weighted mean of its observations' eta.
  const bool given = std::any_of(trajectories_.begin(), trajectories_.end(),
                                 [](const ObservedTrajectory& t) { return !t.contexts.empty(); });
  std::map<std::vector<double>, int> index;
  int contexts = 0;
  for (auto& t : trajectories_) {
    if (given) {
      for (int c : t.contexts) contexts = std::max(contexts, c + 1);
      continue;
    }
    numbered_contexts_ = true;
    t.contexts.resize(static_cast<size_t>(t.num_observations()));
    for (int n = 0; n < t.num_observations(); ++n) {
      std::vector<double> key(t.eta.row(n).data(), t.eta.row(n).data() + t.eta.cols());
      const auto [it, inserted] = index.emplace(std::move(key), static_cast<int>(index.size()));
      t.contexts[static_cast<size_t>(n)] = it->second;
    }
    contexts = static_cast<int>(index.size());
  }
  context_eta_ = RowMatrix::Zero(contexts, 1 + prior_.num_confounders);
  context_observations_ = Eigen::VectorXd::Zero(contexts);
  for (const auto& t : trajectories_) {
    for (int n = 0; n < t.num_observations(); ++n) {
      context_eta_.row(t.context(n)) += t.weight(n) * t.eta.row(n);
      context_observations_[t.context(n)] += t.weight(n);
    }
  }
  if (!given) {
    for (const auto& [key, c] : index)
      context_eta_.row(c) = Eigen::Map<const Eigen::RowVectorXd>(key.data(), context_eta_.cols());
    return;
  }
  for (int c = 0; c < contexts; ++c) {
    if (context_observations_[c] > 0.0)
      context_eta_.row(c) /= context_observations_[c];
    else
      context_eta_.row(c).setConstant(1.0 / static_cast<double>(context_eta_.cols()));
  }
}

std::optional<RowMatrix> ObservationEStep::learned_eta(const ObservationPrior& alpha) const {
  if (num_contexts() == 0 || !alpha.learn || !alpha.learn_eta) return std::nullopt;
  const RowMatrix& parameters = alpha.eta_alpha.rows() == num_contexts() ? alpha.eta_alpha : context_eta_;
  RowMatrix eta = parameters;
  for (Eigen::Index c = 0; c < eta.rows(); ++c) {
    const double total = eta.row(c).sum();
    if (total > 0.0) eta.row(c) /= total;
  }
  return eta;
}

std::optional<LearnedEta> ObservationEStep::learned_eta_report(const ObservationPrior& alpha) const {
  std::optional<RowMatrix> learned = learned_eta(alpha);
  if (!learned) return std::nullopt;
  return LearnedEta{context_eta_, std::move(*learned), context_observations_};
}

EStepState ObservationEStep::initial_state(std::uint64_t seed) const {
  EStepState state;
  state.seed = seed;
  state.alpha = prior_;
  // Tied, EM starts where the tie says (a pair the controlled run never saw at its state's
  // view) and a held O is held there: the weighed prior's mean. Untied, EM starts at the
  // prior's own mean, as it always has.
  if (prior_.subject_base_shape.size() > 0) state.alpha->subject_alpha = weighed_subject_prior(prior_, prior_.strength);
  if (num_contexts() > 0) state.alpha->eta_alpha = prior_.eta_strength * context_eta_;
  return state;
}

std::vector<int> ObservationEStep::trajectory_lengths() const {
  std::vector<int> lengths;
  for (const auto& t : trajectories_) lengths.push_back(t.length());
  return lengths;
}

int ObservationEStep::num_blocks() const {
  return (static_cast<int>(trajectories_.size()) + kBlockSize - 1) / kBlockSize;
}

std::vector<EStepStatistics> ObservationEStep::block_statistics(const SoftSolution& policy,
                                                                const ObservationModel& model, std::uint64_t seed,
                                                                const std::vector<int>& blocks, int threads,
                                                                const RowMatrix* eta) const {
  const int n = static_cast<int>(trajectories_.size());
  const int P = mdp_.num_pairs();
  const int E = model.num_confounders();
  const int W = model.num_symbols();
  for (int b : blocks) {
    if (b < 0 || b >= num_blocks()) throw InputError("block", std::to_string(b) + " is not a block of this data");
  }
  std::vector<EStepStatistics> partial(blocks.size());
  const Rng root(seed);
  // Learned eta: each observation's eta is its context's row.
  std::optional<ObservationKinds> calibrated_kinds;
  if (eta && kinds_) {
    calibrated_kinds = *kinds_;
    for (int k = 0; k < kinds_->num_kinds(); ++k)
      calibrated_kinds->eta.row(k) = eta->row(kinds_->contexts[static_cast<size_t>(k)]);
  }
  const ObservationKinds* kinds = calibrated_kinds ? &*calibrated_kinds : (kinds_ ? &*kinds_ : nullptr);
  std::optional<KindEmissions> table;
  if (kinds) table = kind_emissions(model, *kinds);
  parallel_for(static_cast<int>(blocks.size()), threads, [&](int k) {
    const int b = blocks[static_cast<size_t>(k)];
    std::unique_ptr<PosteriorEngine> engine = options_.engine(mdp_);
    EStepStatistics& out = partial[static_cast<size_t>(k)];
    out = EStepStatistics::zero(P, E, W, num_contexts());
    const int begin = b * kBlockSize, end = std::min(n, (b + 1) * kBlockSize);
    if (table &&
        engine->accumulate_by_kind(policy, model, trajectories_, begin, end, *kinds, *table, options_.watch, out)) {
      return;
    }
    for (int i = begin; i < end; ++i) {
      Rng rng = root.split(static_cast<std::uint64_t>(i));
      if (i == options_.watch) {  // the same sums, and the posterior kept
        const ObservedTrajectory& t = trajectories_[static_cast<size_t>(i)];
        engine->accumulate_watched(policy, model, eta ? with_eta(t, *eta) : t, rng, out);
        continue;
      }
      if (eta) {
        engine->accumulate(policy, model, with_eta(trajectories_[static_cast<size_t>(i)], *eta), rng, out);
      } else {
        engine->accumulate(policy, model, trajectories_[static_cast<size_t>(i)], rng, out);
      }
    }
  });
  return partial;
}

EStepStatistics ObservationEStep::statistics(const SoftSolution& policy, const ObservationModel& model,
                                             std::uint64_t seed, const RowMatrix* eta) const {
  std::vector<EStepStatistics> partial;
  if (options_.executor) {
    partial = options_.executor->run(*this, policy, model, seed, eta);
    if (static_cast<int>(partial.size()) != num_blocks()) {
      throw std::runtime_error("E-step executor returned " + std::to_string(partial.size()) + " blocks, expected " +
                               std::to_string(num_blocks()));
    }
  } else {
    std::vector<int> all(static_cast<size_t>(num_blocks()));
    for (int b = 0; b < num_blocks(); ++b) all[static_cast<size_t>(b)] = b;
    partial = block_statistics(policy, model, seed, all, options_.threads, eta);
  }
  EStepStatistics total =
      EStepStatistics::zero(mdp_.num_pairs(), model.num_confounders(), model.num_symbols(), num_contexts());
  for (const auto& part : partial) total += part;
  return total;
}

EStepStatistics ObservationEStep::cross_fitted_statistics(const SoftSolution& policy, const ObservationPrior& alpha,
                                                          std::uint64_t seed, const RowMatrix* eta) const {
  const int n = static_cast<int>(trajectories_.size());
  const int P = mdp_.num_pairs();
  const ObservationModel model = dirichlet_mean(alpha);
  const int E = model.num_confounders();
  const int W = model.num_symbols();
  // Every trajectory's expected counts under the current O, then each one's own under the
  // same O: O_{-i} is what choose_strength scores trajectory i with.
  const AlphaCounts all = statistics(policy, model, Rng(seed, 1).next_u64(), eta).alpha_dot;
  const Rng own_root(seed, 2);
  std::vector<EStepStatistics> partial(static_cast<size_t>(num_blocks()));
  const Rng root(seed);
  parallel_for(num_blocks(), options_.threads, [&](int b) {
    std::unique_ptr<PosteriorEngine> engine = options_.engine(mdp_);
    EStepStatistics& out = partial[static_cast<size_t>(b)];
    out = EStepStatistics::zero(P, E, W, num_contexts());
    for (int i = b * kBlockSize; i < std::min(n, (b + 1) * kBlockSize); ++i) {
      const ObservedTrajectory& given = trajectories_[static_cast<size_t>(i)];
      std::optional<ObservedTrajectory> calibrated;  // a copy only when learned eta replaces the stated
      if (eta) calibrated = with_eta(given, *eta);
      const ObservedTrajectory& trajectory = calibrated ? *calibrated : given;
      Rng own_rng = own_root.split(static_cast<std::uint64_t>(i));
      EStepStatistics own = EStepStatistics::zero(P, E, W, num_contexts());
      engine->accumulate(policy, model, trajectory, own_rng, own);
      const ObservationModel without = leave_one_out_mean(prior_, alpha.strength, all, own.alpha_dot);
      Rng rng = root.split(static_cast<std::uint64_t>(i));
      if (i == options_.watch)
        engine->accumulate_watched(policy, without, trajectory, rng, out);
      else
        engine->accumulate(policy, without, trajectory, rng, out);
    }
  });
  EStepStatistics total = EStepStatistics::zero(P, E, W, num_contexts());
  for (const auto& part : partial) total += part;
  return total;
}

EStepResult ObservationEStep::expect(const SoftSolution& policy, EStepState& state) const {
  if (!state.alpha) state.alpha = prior_;
  ObservationPrior& alpha = *state.alpha;
  ObservationModel model = dirichlet_mean(alpha);
  std::optional<RowMatrix> eta = learned_eta(alpha);
  EStepResult result;
  result.alpha_converged = !alpha.learn;
  EStepStatistics stats;
  for (int it = 0; it < std::max(1, options_.max_alpha_iterations); ++it) {
    const std::uint64_t call_seed = Rng(state.seed, state.calls++).next_u64();
    const bool cross_fit = options_.cross_fit && alpha.learn && alpha.update == AlphaUpdate::kPosterior;
    stats = cross_fit ? cross_fitted_statistics(policy, alpha, call_seed, eta ? &*eta : nullptr)
                      : statistics(policy, model, call_seed, eta ? &*eta : nullptr);
    if (it == 0) {
      // The objective at the input point (theta, alpha): what EM's convergence test, its
      // acceleration and the choice of restart compare.
      result.log_likelihood = stats.log_likelihood;
      result.objective = stats.log_likelihood + log_prior_term(model, prior_, alpha);
      if (eta) result.objective += log_eta_prior_term(*eta);
    }
    if (!alpha.learn) break;
    update_alpha(alpha, prior_, stats.alpha_dot);
    double eta_change = 0.0;
    if (eta) {
      // The same exact M-step: the Dirichlet posterior of each context's source shares.
      alpha.eta_alpha = prior_.eta_strength * context_eta_ + stats.source_counts;
      std::optional<RowMatrix> next_eta = learned_eta(alpha);
      eta_change = (*next_eta - *eta).cwiseAbs().maxCoeff();
      eta = std::move(next_eta);
    }
    ObservationModel next = dirichlet_mean(alpha);
    // How much O moved where the data can see it: a pair's row counts in proportion to
    // its expected visits (up to one), since rows of pairs the posterior never visits do
    // not change any posterior.
    const Eigen::VectorXd seen = stats.counts.cwiseMin(1.0);
    const Eigen::VectorXd row_change = (next.subject - model.subject).cwiseAbs().rowwise().maxCoeff();
    double change = seen.cwiseProduct(row_change).maxCoeff();
    if (model.num_confounders() > 0)
      change = std::max(change, (next.confounders - model.confounders).cwiseAbs().maxCoeff());
    if (next.end.size() > 0) change = std::max(change, (next.end - model.end).cwiseAbs().maxCoeff());
    change = std::max(change, eta_change);
    model = std::move(next);
    ++result.alpha_iterations;
    if (change <= options_.alpha_tolerance) {
      result.alpha_converged = true;
      break;
    }
  }
  result.counts = std::move(stats.counts);
  result.impossible_trajectories = stats.impossible;
  result.watched = std::move(stats.watched);
  result.watched_log_likelihood = stats.watched_log_likelihood;
  result.mcmc = stats.mcmc;
  return result;
}

ObservedTrajectory ObservationEStep::with_eta(const ObservedTrajectory& trajectory, const RowMatrix& eta) {
  ObservedTrajectory copy = trajectory;
  for (int n = 0; n < trajectory.num_observations(); ++n) copy.eta.row(n) = eta.row(trajectory.context(n));
  return copy;
}

double ObservationEStep::log_eta_prior_term(const RowMatrix& eta) const {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < eta.size(); ++i) {
    const double beta = prior_.eta_strength * context_eta_.data()[i];
    if (beta > 0.0) sum += beta * std::log(eta.data()[i]);
  }
  return sum;
}

EStepResult ObservationEStep::fixed_model_statistics(const SoftSolution& policy, const EStepState& state) const {
  const ObservationPrior& alpha = state.alpha ? *state.alpha : prior_;
  const std::optional<RowMatrix> eta = learned_eta(alpha);
  EStepStatistics s =
      statistics(policy, dirichlet_mean(alpha), Rng(state.seed, state.calls).next_u64(), eta ? &*eta : nullptr);
  EStepResult r;
  r.counts = std::move(s.counts);
  r.log_likelihood = s.log_likelihood;
  r.objective = s.log_likelihood;
  r.impossible_trajectories = s.impossible;
  r.mcmc = s.mcmc;
  return r;
}

std::optional<StrengthChoice> ObservationEStep::choose_strength(const SoftSolution& policy,
                                                                const EStepState& state) const {
  const ObservationPrior& alpha = state.alpha ? *state.alpha : prior_;
  if (!alpha.learn || alpha.update != AlphaUpdate::kPosterior || !alpha.automatic_strength) return std::nullopt;
  std::vector<double> strengths = prior_strength_grid();
  if (std::find(strengths.begin(), strengths.end(), alpha.strength) == strengths.end())
    strengths.push_back(alpha.strength);
  const ObservationModel model = dirichlet_mean(alpha);
  const std::optional<RowMatrix> eta = learned_eta(alpha);
  const std::uint64_t seed = Rng(state.seed, state.calls).next_u64();
  const AlphaCounts all = statistics(policy, model, seed, eta ? &*eta : nullptr).alpha_dot;
  // Per trajectory, its own expected counts at the current posterior, then its
  // log-likelihood under each strength's posterior without them. Each trajectory's
  // numbers land in its own row; the sums run in trajectory order (same bits for any
  // thread count).
  const int n = static_cast<int>(trajectories_.size());
  Eigen::MatrixXd held_out(n, static_cast<Eigen::Index>(strengths.size()));
  const Rng root(seed);
  parallel_for(n, options_.threads, [&](int i) {
    std::unique_ptr<PosteriorEngine> engine = options_.engine(mdp_);
    ExactEngine exact(mdp_);
    std::vector<ObservedTrajectory> one;
    one.push_back(eta ? with_eta(trajectories_[static_cast<size_t>(i)], *eta) : trajectories_[static_cast<size_t>(i)]);
    const ObservedTrajectory& trajectory = one.front();
    // Its observation kinds: each strength's emissions are a log per kind, not per observation.
    const ObservationKinds kinds = *observation_kinds(one, std::numeric_limits<int>::max());
    EStepStatistics own = EStepStatistics::zero(mdp_.num_pairs(), model.num_confounders(), model.num_symbols());
    // By kinds when the engine can, as the E-step's own pass: a log per kind, not per observation.
    if (!options_.engine.exact ||
        !engine->accumulate_by_kind(policy, model, one, 0, 1, kinds, kind_emissions(model, kinds), -1, own)) {
      Rng rng = root.split(static_cast<std::uint64_t>(i));
      engine->accumulate(policy, model, trajectory, rng, own);
    }
    for (size_t k = 0; k < strengths.size(); ++k) {
      const ObservationModel without = leave_one_out_mean(prior_, strengths[k], all, own.alpha_dot);
      held_out(i, static_cast<Eigen::Index>(k)) =
          exact.log_likelihood(policy, trajectory, kinds.of.front(), kind_emissions(without, kinds));
    }
  });
  StrengthChoice choice;
  double best = -std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < strengths.size(); ++k) {
    double total = 0.0;
    for (int i = 0; i < n; ++i) total += held_out(i, static_cast<Eigen::Index>(k));
    if (strengths[k] == alpha.strength) choice.current_score = total;
    if (total > best) {
      best = total;
      choice.best_strength = strengths[k];
    }
  }
  choice.best_score = best;
  // Ties (and changes below rounding) keep the current strength.
  if (!(best > choice.current_score + 1e-9 * std::max(1.0, std::abs(best)))) {
    choice.best_strength = alpha.strength;
    choice.best_score = choice.current_score;
  }
  return choice;
}

}  // namespace hbirl
