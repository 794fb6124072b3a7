#include "learner/estep_observations.hpp"

#include <stdexcept>

#include "learner/input_error.hpp"
#include "learner/parallel.hpp"

namespace hbirl {

EngineFactory exact_engine_factory() {
  return [](const Mdp& mdp) -> std::unique_ptr<PosteriorEngine> { return std::make_unique<ExactPosteriorEngine>(mdp); };
}

ObservationEStep::ObservationEStep(const Mdp& mdp, std::vector<ObservedTrajectory> trajectories,
                                   ObservationPrior prior, ObservationEStepOptions options)
    : mdp_(mdp), prior_(std::move(prior)), options_(std::move(options)) {
  for (const auto& t : trajectories) trajectories_.push_back(merge_identical_observations(t));
  if (trajectories_.empty()) throw InputError("demonstration", "no trajectories with observations");
  if (prior_.subject_alpha.rows() != mdp.num_pairs() || prior_.subject_alpha.cols() != prior_.num_symbols ||
      prior_.confounder_alpha.rows() != prior_.num_confounders || prior_.confounder_alpha.cols() != prior_.num_symbols) {
    throw InputError("observation_model", "alpha has the wrong shape");
  }
  for (size_t i = 0; i < trajectories_.size(); ++i) {
    const ObservedTrajectory& t = trajectories_[i];
    if (t.length() < 1) throw InputError("demonstration[" + std::to_string(i) + "].steps", "is empty");
    if (t.num_observations() > 0 && t.eta.cols() != 1 + prior_.num_confounders) {
      throw InputError("demonstration[" + std::to_string(i) + "].steps", "eta has the wrong number of sources");
    }
  }
  long long rows = 0;
  for (const auto& t : trajectories_) rows += t.num_observations();
  if (options_.max_kinds > 0) {
    kinds_ = observation_kinds(trajectories_, options_.max_kinds);
    if (kinds_ && 4LL * kinds_->num_kinds() > rows) kinds_.reset();
  }
}

EStepState ObservationEStep::initial_state(std::uint64_t seed) const {
  EStepState state;
  state.seed = seed;
  state.alpha = prior_;
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

std::vector<EStepStatistics> ObservationEStep::block_statistics(const SoftSolution& policy, const ObservationModel& model,
                                                                std::uint64_t seed, const std::vector<int>& blocks,
                                                                int threads) const {
  const int n = static_cast<int>(trajectories_.size());
  const int P = mdp_.num_pairs();
  const int E = model.num_confounders();
  const int W = model.num_symbols();
  for (int b : blocks) {
    if (b < 0 || b >= num_blocks()) throw InputError("block", std::to_string(b) + " is not a block of this data");
  }
  std::vector<EStepStatistics> partial(blocks.size());
  const Rng root(seed);
  std::optional<KindEmissions> table;
  if (kinds_) table = kind_emissions(model, *kinds_);
  parallel_for(static_cast<int>(blocks.size()), threads, [&](int k) {
    const int b = blocks[static_cast<size_t>(k)];
    std::unique_ptr<PosteriorEngine> engine = options_.engine(mdp_);
    EStepStatistics& out = partial[static_cast<size_t>(k)];
    out = EStepStatistics::zero(P, E, W);
    ExactEngine* exact = table ? engine->exact() : nullptr;
    if (exact) {
      RowMatrix kind_gamma = RowMatrix::Zero(kinds_->num_kinds(), P);
      std::vector<char> seen(static_cast<size_t>(kinds_->num_kinds()), 0);
      std::vector<int> touched;
      for (int i = b * kBlockSize; i < std::min(n, (b + 1) * kBlockSize); ++i) {
        exact->accumulate(policy, trajectories_[static_cast<size_t>(i)], kinds_->of[static_cast<size_t>(i)], *table, out,
                          kind_gamma, seen, touched);
      }
      add_kind_alpha_dot(model, *kinds_, *table, kind_gamma, touched, out.alpha_dot);
      return;
    }
    for (int i = b * kBlockSize; i < std::min(n, (b + 1) * kBlockSize); ++i) {
      Rng rng = root.split(static_cast<std::uint64_t>(i));
      engine->accumulate(policy, model, trajectories_[static_cast<size_t>(i)], rng, out);
    }
  });
  return partial;
}

EStepStatistics ObservationEStep::statistics(const SoftSolution& policy, const ObservationModel& model,
                                             std::uint64_t seed) const {
  std::vector<EStepStatistics> partial;
  if (options_.executor) {
    partial = options_.executor->run(*this, policy, model, seed);
    if (static_cast<int>(partial.size()) != num_blocks()) {
      throw std::runtime_error("E-step executor returned " + std::to_string(partial.size()) + " blocks, expected " +
                               std::to_string(num_blocks()));
    }
  } else {
    std::vector<int> all(static_cast<size_t>(num_blocks()));
    for (int b = 0; b < num_blocks(); ++b) all[static_cast<size_t>(b)] = b;
    partial = block_statistics(policy, model, seed, all, options_.threads);
  }
  EStepStatistics total = EStepStatistics::zero(mdp_.num_pairs(), model.num_confounders(), model.num_symbols());
  for (const auto& part : partial) total += part;
  return total;
}

EStepResult ObservationEStep::expect(const SoftSolution& policy, EStepState& state) const {
  if (!state.alpha) state.alpha = prior_;
  ObservationPrior& alpha = *state.alpha;
  ObservationModel model = dirichlet_mean(alpha);
  EStepResult result;
  result.alpha_converged = !alpha.learn;
  EStepStatistics stats;
  for (int it = 0; it < std::max(1, options_.max_alpha_iterations); ++it) {
    const std::uint64_t call_seed = Rng(state.seed, state.calls++).next_u64();
    stats = statistics(policy, model, call_seed);
    if (!alpha.learn) break;
    update_alpha(alpha, stats.alpha_dot, alpha.c);
    ObservationModel next = dirichlet_mean(alpha);
    // How much O moved where the data can see it: a pair's row counts in proportion to
    // its expected visits (up to one), since rows of pairs the posterior never visits do
    // not change any posterior while they slowly forget their prior.
    const Eigen::VectorXd seen = stats.counts.cwiseMin(1.0);
    const Eigen::VectorXd row_change = (next.subject - model.subject).cwiseAbs().rowwise().maxCoeff();
    double change = seen.cwiseProduct(row_change).maxCoeff();
    if (model.num_confounders() > 0) change = std::max(change, (next.confounders - model.confounders).cwiseAbs().maxCoeff());
    model = std::move(next);
    ++result.alpha_iterations;
    if (change <= options_.alpha_tolerance) {
      result.alpha_converged = true;
      break;
    }
  }
  result.counts = std::move(stats.counts);
  result.log_likelihood = stats.log_likelihood;
  result.impossible_trajectories = stats.impossible;
  return result;
}

}  // namespace hbirl
