#pragma once
// The E-step on observations (paper Algorithm 1; docs/MODEL.md): for a policy, compute the
// posterior over each trajectory with a posterior engine (exact forward-backward by
// default, or the paper's MCMC), and refine the observation model inside:
//   repeat: statistics = sum over trajectories of engine(policy, O)
//           alpha = prior(s) + alpha_dot  (the posterior update, the default), or
//           alpha = c * alpha_dot + (1 - c) * alpha  (the paper's);  O = Dirichlet mean of alpha
//   until O stops changing (alpha_tolerance, weighted by how much the data see each row);
// observation_model.hpp has both. The posterior update's s is chosen
// between EM runs (choose_strength, called by HiddenDataEM once EM has converged).
// The refined alpha is carried to the next EM iteration in the EStepState (warm start);
// the first call starts from the prior. An E-step call makes at most
// max_alpha_iterations refinements and reports whether O converged; HiddenDataEM only
// stops once it has, so the loop of Algorithm 1 runs to convergence interleaved with the
// M-steps rather than from scratch for every intermediate theta (same fixed point, a
// fraction of the forward-backward passes). With learn = false, O is the prior's mean.
#include <memory>

#include "learner/estep.hpp"
#include "learner/estep_exact.hpp"
#include "learner/rng.hpp"

namespace hbirl {

// The exact engine's factory (estep_exact.hpp), the E-step's default.
EngineFactory exact_engine_factory();

class ObservationEStep;

// Computes an E-step pass's blocks somewhere else -- e.g. on sampler workers over a bus
// (services/). run() must return, for every block b in [0, estep.num_blocks()), exactly
// what estep.block_statistics(policy, model, seed, {b}, 1, eta) returns, in block order;
// the pass then sums them in that order, so the result is bit-identical to a local pass.
// `eta`: learned eta, one row per context of the E-step (null: the stated eta). run() is
// not const: a pass changes the executor (what it sent, whom it trusts).
class BlockExecutor {
 public:
  virtual ~BlockExecutor() = default;
  virtual std::vector<EStepStatistics> run(const ObservationEStep& estep, const SoftSolution& policy,
                                           const ObservationModel& model, std::uint64_t seed,
                                           const RowMatrix* eta = nullptr) = 0;
};

struct ObservationEStepOptions {
  EngineFactory engine = exact_engine_factory();
  // O has converged when max_r min(1, N_hat(r)) * max_w |O_new(r, w) - O(r, w)| and the
  // confounders' max |O_new - O| are at most this.
  double alpha_tolerance = 1e-4;
  int max_alpha_iterations = 10;  // per E-step call
  int threads = 1;                // over blocks of trajectories; the result does not depend on it
  // The exact engine computes the emission of each distinct (symbol, eta) observation once
  // per pass when the data have at most this many kinds, and at most a quarter as many
  // kinds as observations (0: never). Same result to rounding.
  int max_kinds = 1024;
  // Set: use the kind table (within max_kinds) or not, whatever the data's ratio of kinds to
  // observations. An E-step over some blocks of a larger data set (a sampler worker's share,
  // services/sampler_worker.hpp) must decide as the whole data set's E-step did, or its
  // sums differ from that E-step's in the last bits. Unset: decided from the data.
  std::optional<bool> kind_table;
  // Where the blocks of a pass are computed: null = here, on `threads` threads.
  std::shared_ptr<BlockExecutor> executor;
  // Keep this trajectory's posterior from every pass (the exact engine; -1: none): what a
  // display shows of the E-step without computing it again (EStepResult::watched).
  int watch = -1;
  // Cross-fitted passes (docs/MODEL.md, "Cross-fitting", a diagnostic, not the default):
  // with the posterior update, each trajectory's posterior is taken under O_{-i}
  // (leave_one_out_mean: the Dirichlet posterior from the other trajectories' expected
  // counts), so that what a trajectory guesses of its own path does not also vote for the
  // model it is judged by. Learned eta is not left out. Costs a pass and two forward-backward
  // passes per trajectory; computed here (refused with an executor).
  bool cross_fit = false;
};

// Learned eta as a report shows it: per context (row), the eta its observations stated
// (their mean), the learned one, and how many observations it covers.
struct LearnedEta {
  RowMatrix stated;
  RowMatrix learned;
  Eigen::VectorXd observations;
};

class ObservationEStep final : public EStep {
 public:
  ObservationEStep(const Mdp& mdp, const std::vector<ObservedTrajectory>& trajectories, ObservationPrior prior,
                   ObservationEStepOptions options = {});
  // The same, taking the trajectories over (merged in place, one at a time: the data are
  // never held twice). Refused, it throws with them left as they were.
  ObservationEStep(const Mdp& mdp, std::vector<ObservedTrajectory>&& trajectories, ObservationPrior prior,
                   ObservationEStepOptions options = {});

  // The learned source distribution of each context at `alpha` (its eta_alpha's mean),
  // or null when eta is not learned.
  std::optional<RowMatrix> learned_eta(const ObservationPrior& alpha) const;
  // The same with each context's stated eta and observations, for reports.
  std::optional<LearnedEta> learned_eta_report(const ObservationPrior& alpha) const;

  EStepState initial_state(std::uint64_t seed) const override;
  EStepResult expect(const SoftSolution& policy, EStepState& state) const override;
  bool depends_on_policy() const override { return true; }
  EStepResult fixed_model_statistics(const SoftSolution& policy, const EStepState& state) const override;
  // The posterior update's subject prior strength s, when automatic: for every s on
  // prior_strength_grid() and each trajectory i, log Pr(trajectory i | theta, O_{-i}(s))
  // with O_{-i}(s) the mean of the Dirichlet posterior from the prior and the other
  // trajectories' expected counts (at the current posterior); the s with the largest sum.
  std::optional<StrengthChoice> choose_strength(const SoftSolution& policy, const EStepState& state) const override;
  std::vector<int> trajectory_lengths() const override;

  // The posterior statistics for one observation model, summed over trajectories in a
  // fixed order of fixed-size blocks (bit-identical for any thread count, and for any
  // executor that honours its contract).
  // With `eta` (one row per context) the observations' eta is replaced by their
  // context's row (learned eta); null keeps the stated eta.
  EStepStatistics statistics(const SoftSolution& policy, const ObservationModel& model, std::uint64_t seed,
                             const RowMatrix* eta = nullptr) const;

  // The blocks: trajectories [b * kBlockSize, (b + 1) * kBlockSize) form block b.
  static constexpr int kBlockSize = 16;
  int num_blocks() const;
  // The statistics of the listed blocks, in the order listed, computed here on `threads`
  // threads (the values do not depend on it).
  std::vector<EStepStatistics> block_statistics(const SoftSolution& policy, const ObservationModel& model,
                                                std::uint64_t seed, const std::vector<int>& blocks, int threads = 1,
                                                const RowMatrix* eta = nullptr) const;
  // Learned eta's contexts: their number and stated eta (one row each); 0 when eta is not learned.
  int num_contexts() const { return static_cast<int>(context_eta_.rows()); }
  const RowMatrix& context_eta() const { return context_eta_; }
  // How many observations each context covers (their multiplicities summed).
  const Eigen::VectorXd& context_observations() const { return context_observations_; }
  const Mdp& mdp() const { return mdp_; }

  const std::vector<ObservedTrajectory>& trajectories() const { return trajectories_; }
  // The trajectories handed over as they were given, merged (merging them again gives them
  // unchanged; contexts this E-step numbered are taken off), leaving this E-step empty: for
  // a holder that lends its data to an E-step and takes it back rather than keep a copy
  // (services/sampler_worker.cpp).
  std::vector<ObservedTrajectory> take_trajectories() &&;
  // The digest (dataset_digest) of the trajectories as given, merged, before learned eta
  // gave them contexts: how a BlockExecutor tells the E-steps it serves apart (the
  // trajectories it sends workers are trajectories(), contexts included). Set only with an
  // executor.
  std::uint64_t input_digest() const { return input_digest_; }
  // The trajectory with each observation's eta replaced by its context's row of `eta`
  // (learned_eta): what the learned model believes of each observation's source.
  static ObservedTrajectory with_eta(const ObservedTrajectory& trajectory, const RowMatrix& eta);
  // Whether the exact engine's passes use one emission per observation kind (see max_kinds).
  bool uses_kind_table() const { return kinds_.has_value(); }
  const ObservationPrior& prior() const { return prior_; }
  const ObservationEStepOptions& options() const { return options_; }

 private:
  // Learned eta: gives every observation a context (each distinct eta, unless given) and
  // fills context_eta_.
  void assign_contexts();
  bool learns_eta() const { return prior_.learn && prior_.learn_eta && prior_.num_confounders > 0; }
  // Refuses data this E-step cannot use (InputError naming the field), before it takes any.
  void check_data(const std::vector<ObservedTrajectory>& trajectories) const;
  // Reads the merged trajectories for the digest, the contexts and the kind table.
  void finish();
  // statistics() with each trajectory's posterior under O_{-i} (options.cross_fit) at
  // alpha's strength, the counts left out those under alpha's mean.
  EStepStatistics cross_fitted_statistics(const SoftSolution& policy, const ObservationPrior& alpha, std::uint64_t seed,
                                          const RowMatrix* eta) const;
  // sum over contexts and sources of eta_strength * stated eta * log(learned eta).
  double log_eta_prior_term(const RowMatrix& eta) const;

  const Mdp& mdp_;
  std::vector<ObservedTrajectory> trajectories_;
  std::optional<ObservationKinds> kinds_;
  RowMatrix context_eta_;
  Eigen::VectorXd context_observations_;
  std::uint64_t input_digest_ = 0;
  bool numbered_contexts_ = false;  // assign_contexts gave the observations their contexts
  ObservationPrior prior_;
  ObservationEStepOptions options_;
};

}  // namespace hbirl
