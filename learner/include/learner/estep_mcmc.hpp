#pragma once
// The paper's E-step engine (paper appendix, Algorithms 1-2; docs/MODEL.md "The E-step on observations"):
// Metropolis-within-Gibbs over the source labels Z, the states s and the actions a of a
// trajectory. Every node is updated by the paper's "Sample" step: propose a value
// uniformly, accept with probability min(1, Pr(new | rest) / Pr(old | rest)), using
//   Pr(Z_n = z | .) ∝ eta_n(z) O_z(w_n)            (O_0 = O_{s_t, a_t})
//   Pr(s_t | .)     ∝ pi(a_t|s_t) T(s_t|s_{t-1},a_{t-1}) T(s_{t+1}|s_t,a_t) prod_{n: Z_n=0} O_{s_t,a_t}(w_n)
//   Pr(a_t | .)     ∝ pi(a_t|s_t) T(s_{t+1}|s_t,a_t) prod_{n: Z_n=0} O_{s_t,a_t}(w_n)
// in log space (the paper's implementation note). When every transition is
// deterministic, single-site moves of s or a cannot leave the current trajectory, so the
// states and actions are instead resampled as a block: a trajectory is proposed from the
// MDP under the policy and accepted with the ratio of its observation likelihoods (an
// independence Metropolis-Hastings move whose proposal is the prior). Single-site moves
// can also be reducible with sparse stochastic transitions (s_t must be reachable from
// the previous step and reach the next one); Block::kAlways adds the block move then.
//
// Marginals, source posteriors, expected visits and alpha_dot are sample averages over
// `samples` sweeps after `burn_in`, per chain, over `chains` chains. The log-likelihood
// cannot be estimated from the chain; it is computed exactly by the forward algorithm.
//
// Every run of the chains also reports whether they can be trusted (docs/MODEL.md, "Is
// the MCMC E-step converged?"): the rank-normalised split-R-hat and the bulk ESS
// (mcmc_diagnostics.hpp) of every (step, pair) marginal it outputs, whose draws are the
// indicators "the path is at that pair at that step"; the worst of them go to
// TrajectoryPosterior::mcmc and EStepStatistics::mcmc.
#include "learner/estep_exact.hpp"
#include "learner/estep_observations.hpp"

namespace hbirl {

struct McmcOptions {
  int samples = 1000;  // sweeps kept per chain (sigma)
  int burn_in = 200;   // sweeps discarded per chain
  int chains = 1;
  // Path moves: kAuto (the paper) replaces the single-site s, a updates by the block move
  // when every transition is deterministic; kAlways adds the block move to the
  // single-site updates (needed when sparse stochastic transitions make single-site moves
  // reducible); kOnly uses block moves alone; kNever never.
  enum class Block { kAuto, kAlways, kOnly, kNever } block = Block::kAuto;
};

class McmcEngine final : public PosteriorEngine {
 public:
  McmcEngine(const Mdp& mdp, McmcOptions options);
  TrajectoryPosterior posterior(const SoftSolution& policy, const ObservationModel& model,
                                const ObservedTrajectory& trajectory, Rng& rng) override;
  void accumulate(const SoftSolution& policy, const ObservationModel& model, const ObservedTrajectory& trajectory,
                  Rng& rng, EStepStatistics& out) override;

 private:
  // Runs the chains; fills marginals (T x P), per-observation source frequencies,
  // alpha_dot and the chains' convergence diagnostics. Returns false if no trajectory of
  // positive probability was found.
  bool sample(const SoftSolution& policy, const ObservationModel& model, const ObservedTrajectory& trajectory, Rng& rng,
              RowMatrix& marginals, RowMatrix& sources, AlphaCounts& alpha_dot, McmcDiagnostics& diagnostics);

  const Mdp& mdp_;
  McmcOptions options_;
  bool single_site_ = true;
  bool block_ = false;
  ExactEngine exact_;  // for the log-likelihood only
};

EngineFactory mcmc_engine_factory(McmcOptions options);

}  // namespace hbirl
