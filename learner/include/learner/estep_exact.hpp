#pragma once
// The exact E-step engine (docs/MODEL.md "The E-step on observations"). The source label Z of each observation is
// summed out,
//   p(w | s,a) = eta(0) O_{s,a}(w) + sum_e eta(e) O_e(w),
// so a trajectory is a chain over (s, a) pairs with emission prod_n p(w_n | s_t, a_t) at
// step t, solved exactly by forward-backward. Emissions are sums of logs (thousands of
// observations per step cannot underflow). The passes run in linear space with
// Rabiner's scaling while a bound on what that can lose stays under 1e-30 of what is
// kept, else in log space (log-sum-exp over the sparse transitions), so deterministic
// transitions, occluded steps (no observations: emission 1), long trajectories and
// evidence thousands of nats apart are all exact (docs/MODEL.md "The E-step on
// observations").
// The posteriors of Z and the expected counts alpha_dot follow in closed form from the
// (s, a) marginals:
//   Pr(Z = 0 | data) = sum_r gamma_t(r) eta(0) O_r(w) / p(w | r)
//   Pr(Z = e | data) = sum_r gamma_t(r) eta(e) O_e(w) / p(w | r).
#include <functional>
#include <memory>
#include <vector>

#include "learner/mcmc_diagnostics.hpp"
#include "learner/mdp.hpp"
#include "learner/observation_model.hpp"
#include "learner/rng.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl {

struct TrajectoryPosterior {
  double log_likelihood = 0.0;  // log Pr(observations | theta, O); -inf if impossible
  RowMatrix marginals;          // T x (S*A): Pr(s_t = s, a_t = a | data)
  RowMatrix sources;            // one row per observation: Pr(Z = z | data), subject first
  // Pr(the last action entered s | data) per state when the trajectory ended in a terminal
  // state (what the end sensor's expected counts are made of); empty otherwise.
  Eigen::VectorXd end_states;
  McmcDiagnostics mcmc;  // the MCMC engine's convergence diagnostics (neutral otherwise)
};

// What the E-step sums over trajectories.
struct EStepStatistics {
  Eigen::VectorXd counts;  // expected visits per (s, a) pair
  AlphaCounts alpha_dot;   // expected source-labelled counts
  // Expected number of observations of each context (rows) made by each source
  // (columns): what learned eta is fitted to. Only filled when it has rows (contexts > 0)
  // and the observations carry contexts.
  RowMatrix source_counts;
  double log_likelihood = 0.0;
  int impossible = 0;  // trajectories with probability 0 under the model (skipped)
  // The watched trajectory's posterior (ObservationEStepOptions::watch), when this sum
  // holds it: its (s, a) marginals per step (steps x pairs) and its log-likelihood.
  RowMatrix watched;
  double watched_log_likelihood = 0.0;
  // The MCMC engine's worst convergence diagnostics over the trajectories' pair marginals
  // (mcmc_diagnostics.hpp); neutral for the exact engine and for blocks from the bus,
  // which does not carry them. Summed with max / min: the same bits in any order.
  McmcDiagnostics mcmc;

  static EStepStatistics zero(int pairs, int confounders, int symbols, int contexts = 0);
  EStepStatistics& operator+=(const EStepStatistics& other);
};

// The emission of every observation kind (observations.hpp) under one observation
// model: computed once per E-step pass and shared by all trajectories.
struct KindEmissions {
  RowMatrix p;          // kinds x (S*A): p(w | s,a) = eta(0) O_{s,a}(w) + sum_e eta(e) O_e(w)
  RowMatrix log_p;      // its log
  Eigen::MatrixXd end;  // the model's O_end, for the trajectories' end symbols
};
KindEmissions kind_emissions(const ObservationModel& model, const ObservationKinds& kinds);

// alpha_dot from each kind's posterior weight G(k, r) = sum over the observations n of kind k
// of weight_n gamma_{t(n)}(r) (ExactEngine::accumulate with kinds): the closed forms above,
// summed per kind. Only the kinds listed in `touched` are read.
// Also adds each kind's expected observations per source to row kinds.contexts[k] of
// `source_counts` when that has rows.
void add_kind_alpha_dot(const ObservationModel& model, const ObservationKinds& kinds, const KindEmissions& emissions,
                        const RowMatrix& kind_gamma, const std::vector<int>& touched, AlphaCounts& out,
                        RowMatrix& source_counts);

// One trajectory's posterior and its E-step statistics, by whatever method: exactly by
// forward-backward (ExactEngine below) or by the paper's MCMC (McmcEngine,
// estep_mcmc.hpp). The E-step on observations (estep_observations.hpp) makes one engine per
// block of trajectories (each has its own workspace) and asks it for their statistics.
class PosteriorEngine {
 public:
  virtual ~PosteriorEngine() = default;
  virtual TrajectoryPosterior posterior(const SoftSolution& policy, const ObservationModel& model,
                                        const ObservedTrajectory& trajectory, Rng& rng) = 0;
  // Adds the trajectory's expected visits, alpha_dot and log-likelihood to `out`.
  virtual void accumulate(const SoftSolution& policy, const ObservationModel& model,
                          const ObservedTrajectory& trajectory, Rng& rng, EStepStatistics& out) = 0;
  // The same, also keeping its posterior as out.watched (ObservationEStepOptions::watch)
  // when the engine computes one exactly; a sampling engine adds as accumulate() does.
  virtual void accumulate_watched(const SoftSolution& policy, const ObservationModel& model,
                                  const ObservedTrajectory& trajectory, Rng& rng, EStepStatistics& out) {
    accumulate(policy, model, trajectory, rng, out);
  }
  // The statistics of trajectories[begin, end), whose observations are grouped by kind
  // (`kinds`, with the kinds' emissions `table` computed once per pass), added to `out`
  // with trajectory `watch`'s posterior kept -- when the engine can share emissions across
  // kinds. Returns false, having added nothing, when it cannot (then accumulate() is
  // called for each trajectory).
  virtual bool accumulate_by_kind(const SoftSolution&, const ObservationModel&, const std::vector<ObservedTrajectory>&,
                                  int /*begin*/, int /*end*/, const ObservationKinds&, const KindEmissions&,
                                  int /*watch*/, EStepStatistics&) {
    return false;
  }
};

// Makes a fresh engine for an MDP (which must outlive it), and says whether its engines are
// exact: their statistics then do not depend on the random stream, and equal the kinds'
// shared sums (services/ checks a sampler worker's answers against its own when exact).
struct EngineFactory {
  std::function<std::unique_ptr<PosteriorEngine>(const Mdp&)> make;
  bool exact = false;  // (a factory says so: a sampler claiming exactness would be spot-checked wrongly)
  std::unique_ptr<PosteriorEngine> operator()(const Mdp& mdp) const { return make(mdp); }
};

class ExactEngine;
// ExactEngine::accumulate by kinds for trajectories[k], k in [begin, end), whose kinds are
// kinds.of[k], then add_kind_alpha_dot: their expected visits, log-likelihoods and alpha_dot
// added to `out` (trajectory `watch`'s marginals kept, as accumulate does).
void accumulate_by_kind(ExactEngine& exact, const SoftSolution& policy, const ObservationModel& model,
                        const std::vector<ObservedTrajectory>& trajectories, int begin, int end,
                        const ObservationKinds& kinds, const KindEmissions& table, int watch, EStepStatistics& out);

// Forward-backward workspace bound to one MDP (which must outlive it): the exact engine.
class ExactEngine final : public PosteriorEngine {
 public:
  explicit ExactEngine(const Mdp& mdp);

  // The engine's interface; the random stream is not used.
  TrajectoryPosterior posterior(const SoftSolution& policy, const ObservationModel& model,
                                const ObservedTrajectory& trajectory, Rng&) override {
    return posterior(policy, model, trajectory);
  }
  void accumulate(const SoftSolution& policy, const ObservationModel& model, const ObservedTrajectory& trajectory, Rng&,
                  EStepStatistics& out) override {
    accumulate(policy, model, trajectory, out);
  }
  void accumulate_watched(const SoftSolution& policy, const ObservationModel& model,
                          const ObservedTrajectory& trajectory, Rng&, EStepStatistics& out) override {
    accumulate(policy, model, trajectory, out, true);
  }
  bool accumulate_by_kind(const SoftSolution& policy, const ObservationModel& model,
                          const std::vector<ObservedTrajectory>& trajectories, int begin, int end,
                          const ObservationKinds& kinds, const KindEmissions& table, int watch,
                          EStepStatistics& out) override {
    hbirl::accumulate_by_kind(*this, policy, model, trajectories, begin, end, kinds, table, watch, out);
    return true;
  }

  TrajectoryPosterior posterior(const SoftSolution& policy, const ObservationModel& model,
                                const ObservedTrajectory& trajectory);
  // log Pr(observations | theta, O) by the forward pass alone.
  double log_likelihood(const SoftSolution& policy, const ObservationModel& model,
                        const ObservedTrajectory& trajectory) {
    return forward_backward(policy, model, trajectory, false);
  }
  // The same with the emissions of the trajectory's observation kinds precomputed (see
  // accumulate below): the same number, without a log per observation and pair.
  double log_likelihood(const SoftSolution& policy, const ObservedTrajectory& trajectory,
                        const std::vector<int>& kinds_of, const KindEmissions& table) {
    emissions(trajectory, kinds_of, table);
    end_evidence(trajectory, table.end);
    return passes(policy, trajectory, false);
  }
  // Adds the trajectory's expected visits, alpha_dot and log-likelihood to `out` (and,
  // when `watch`, its marginals and log-likelihood as out.watched).
  void accumulate(const SoftSolution& policy, const ObservationModel& model, const ObservedTrajectory& trajectory,
                  EStepStatistics& out, bool watch = false);
  // The same with the emissions of the trajectory's observation kinds (`kinds_of`, one per
  // observation row) precomputed: adds the expected visits and the log-likelihood to
  // `out`, and weight_n * gamma_t to row kinds_of[n] of kind_gamma (kinds x pairs), from
  // which add_kind_alpha_dot gives alpha_dot. Kinds seen for the first time (a zero entry
  // in `seen`) are appended to `touched`.
  void accumulate(const SoftSolution& policy, const ObservedTrajectory& trajectory, const std::vector<int>& kinds_of,
                  const KindEmissions& emissions, EStepStatistics& out, RowMatrix& kind_gamma, std::vector<char>& seen,
                  std::vector<int>& touched, bool watch = false);
  // Whether the last trajectory went through the scaled passes (else the log-space ones);
  // tests check that both are covered.
  bool last_passes_scaled() const { return scaled_; }

 private:
  // Fills log_emission_, log_alpha_ and (with_backward) log_beta_; returns the
  // log-likelihood.
  double forward_backward(const SoftSolution& policy, const ObservationModel& model,
                          const ObservedTrajectory& trajectory, bool with_backward = true);
  // The log emissions of each step into log_emission_, per observation (filling p_) or
  // from the kinds' table.
  void emissions(const ObservationModel& model, const ObservedTrajectory& trajectory);
  void emissions(const ObservedTrajectory& trajectory, const std::vector<int>& kinds_of, const KindEmissions& table);
  // Forward and backward passes over log_emission_; returns the log-likelihood. The
  // scaled passes when they are exact to rounding, else the log-space ones.
  double passes(const SoftSolution& policy, const ObservedTrajectory& trajectory, bool with_backward);
  // Rabiner's scaled forward-backward in linear space (docs/MODEL.md "The E-step on
  // observations"): alpha_hat_, beta_hat_, emission_, scale_, normaliser_. NaN when a
  // message would leave the range where that is exact (then log_passes decides).
  double scaled_passes(const SoftSolution& policy, const ObservedTrajectory& trajectory, bool with_backward);
  // Its parts: the forward pass (the sum of the steps' log scales; -inf when no pair can
  // emit a step's observations), the last step's backward message (the log normaliser), and
  // the backward pass (false when it would leave the exact range). NaN: not exact here.
  double scaled_forward(const SoftSolution& policy, const ObservedTrajectory& trajectory);
  double scaled_end(const ObservedTrajectory& trajectory);
  bool scaled_backward(const SoftSolution& policy, int T);
  // The same in log space (log_alpha_, log_beta_): exact for any spread of emissions.
  double log_passes(const SoftSolution& policy, const ObservedTrajectory& trajectory, bool with_backward);
  // The logs of the transitions and the start, made on the first need for log_passes
  // (most engines, one per E-step block, never need them).
  void prepare_log_space();
  // For a trajectory of log-likelihood ll (counted impossible if -inf): adds ll and the
  // marginals to `out`, calling per_observation(n) for each observation with marginal_
  // holding its step's marginals.
  template <typename PerObservation>
  void add_marginals(const ObservedTrajectory& trajectory, double ll, EStepStatistics& out, bool watch,
                     PerObservation&& per_observation);
  // gamma_t = alpha_t beta_t / Pr(observations) into marginal_.
  void marginal(int t, double log_likelihood);
  // p(w | r) of observation n for every pair, into row n of p_.
  void mixture(const ObservationModel& model, const ObservedTrajectory& trajectory, int n);
  // What the trajectory's end says (end_log_evidence) into end_log_, under O_end `end_model`.
  void end_evidence(const ObservedTrajectory& trajectory, const Eigen::MatrixXd& end_model);
  // Pr(the last action entered s | data) into entered_, from the last step's marginals in
  // marginal_: sum_r gamma(r) T(s | r) e(s) / sum_s' T(s' | r) e(s'), e = exp end_log_.
  void entered_state_posterior();
  // The end sensor's expected counts: entered_ once per end symbol (docs/MODEL.md
  // "Sensors that see the end").
  void add_end_counts(const ObservedTrajectory& trajectory, int end_symbols, AlphaCounts& out);

  const Mdp& mdp_;
  SparseRowMatrix incoming_;         // S x (S*A), T transposed
  SparseRowMatrix log_transitions_;  // (S*A) x S, log T (prepare_log_space)
  SparseRowMatrix log_incoming_;     // S x (S*A), log T transposed (prepare_log_space)
  Eigen::VectorXd log_start_;        // (prepare_log_space)
  RowMatrix log_emission_;           // T x (S*A)
  RowMatrix log_alpha_;
  RowMatrix log_beta_;
  bool scaled_ = false;          // the last passes were the scaled ones
  RowMatrix alpha_hat_;          // T x (S*A): Pr(r at t | observations up to t)
  RowMatrix beta_hat_;           // T x (S*A): the backward messages over the later scales
  RowMatrix emission_;           // T x (S*A): exp(log_emission_ - m_t)
  Eigen::VectorXd scale_;        // c_t
  Eigen::VectorXd lost_;         // log of a bound on the forward mass lost by step t, in units of alpha_hat_t
  double normaliser_ = 1.0;      // sum_r alpha_hat_{T-1} beta_{T-1}
  double backward_total_ = 1.0;  // sum_r alpha_hat_t beta_hat_t (normaliser_, or 1 when that was small)
  Eigen::VectorXd prior_;        // per pair: d_t(s) pi(a|s) (forward); pi e beta_hat (backward)
  Eigen::VectorXd marginal_;
  RowMatrix p_;           // one row per observation: p(w | r) per pair (kept for the posteriors)
  Eigen::ArrayXd ratio_;  // gamma / p of one observation
  Eigen::VectorXd scratch_;
  Eigen::VectorXd end_log_;    // per state: log Pr(end | the last action entered it)
  int end_symbols_ = 0;        // K, the end alphabet of the model end_log_ was made under
  Eigen::VectorXd entered_;    // per state: Pr(the last action entered it | data)
  Eigen::ArrayXd shift_;       // per pair, backward pass
  Eigen::VectorXd shifted_;    // log_product's workspace
  Eigen::VectorXd previous_;   // log alpha of the step before, forward pass
  Eigen::VectorXd row_;        // log beta of one step, backward pass
  std::vector<int> low_rows_;  // log_product's rows summed again in log space
};

}  // namespace hbirl
