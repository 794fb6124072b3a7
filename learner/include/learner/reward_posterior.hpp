#pragma once
// The posterior over the reward weights (docs/MODEL.md "The posterior over theta"):
//     p(theta | data) ∝ p(data | theta, O) N(theta; 0, sigma^2 I),
// with the observation model O (and learned eta) held at the values EM learned -- what
// that leaves out is their own uncertainty, which makes the posterior somewhat narrower
// than the full one (app::learn averages the confidence over O as learned and O at the
// prior, docs/MODEL.md).
//
// log p(data | theta, O) is the E-step's (EStep::fixed_model_statistics): the exact
// forward-backward's log-likelihood of the observations, or sum log pi(a|s) on true
// trajectories; its gradient, by Fisher's identity, is MaxCausalEnt's gradient with the
// posterior's expected visits at theta itself (maxcausalent.hpp).
//
// Samples by importance sampling from the Laplace approximation: the posterior's mode
// (L-BFGS from EM's theta), the Hessian there by central differences of the gradient,
// then draws from a Student-t (4 degrees of freedom: heavier tails than the posterior's)
// centred at the mode with that curvature, each weighted by posterior / proposal. The
// weights make every summary consistent whatever the Laplace approximation misses (skew,
// a saturating likelihood); their effective number says how well the proposal covered it.
//
// sigma: given (8 unless told), or chosen by the evidence (empirical Bayes): the Laplace
// approximation of log p(data | sigma) over a grid of scales, from the likelihood's
// curvature at EM's theta -- measured worse calibrated than 8 (docs/MODEL.md).
#include <cstdint>
#include <vector>

#include "learner/estep.hpp"
#include "learner/mdp.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl {

// The draws the calibration experiment asks for: the confidence to about +-0.035 when they
// are worth as many independent ones (hbirl learn warns when the importance weights make
// them worth a tenth).
constexpr int kConfidenceDraws = 200;
// The draws of a live estimate (services/launch.sh, hbirl-optimiser --anytime) and of the
// stopping experiment that models it: half, so that the update after a demonstration of the
// onion demo fits in 200 ms on two cores (docs/BENCHMARKS.md). Calibrated as well on tasks
// nothing was chosen on (docs/results/calibration_live_draws, seeds 7001-7200: from
// observations AUROC 0.821, ECE 0.079, 88.4% right at >= 0.9; 200 draws: 0.825, 0.079, 89.0%).
constexpr int kLiveConfidenceDraws = 100;

struct RewardPosteriorOptions {
  int samples = 0;  // importance draws (at least 1; front ends draw none unless asked)
  // sigma. 8: weakly informative for features of order 1 (indicators, as in the built-in
  // domains and random tasks), and the confidence it gives measured calibrated on held-out
  // random tasks (docs/MODEL.md "The posterior over theta"); 0: chosen by the evidence.
  double prior_scale = 8.0;
  std::uint64_t seed = 1;
  double student_dof = 4.0;  // the proposal's degrees of freedom
};

// Throws InputError naming the option out of range (what sample_reward_posterior checks
// first; a front end checks before it learns).
void check_posterior_options(const RewardPosteriorOptions& options);

// The evidence's grid of prior scales (0: sigma chosen on it).
std::vector<double> prior_scale_grid();

// log p(data | theta, O) + log N(theta; 0, sigma^2 I) (without its constant), and its gradient.
class RewardLogPosterior {
 public:
  // `state`: the E-step's state EM ended in (its learned observation model); all must
  // outlive this.
  RewardLogPosterior(const Mdp& mdp, const EStep& estep, const EStepState& state, double prior_scale,
                     SoftViOptions soft_vi = {});
  double evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient);
  // Of the last evaluate(): log p(data | theta, O) alone.
  double log_likelihood() const { return log_likelihood_; }
  double prior_scale() const { return prior_scale_; }
  int evaluations() const { return evaluations_; }

 private:
  const Mdp& mdp_;
  const EStep& estep_;
  const EStepState& state_;
  double prior_scale_;
  SoftViOptions soft_vi_;
  SoftBellmanSolver solver_;
  double log_likelihood_ = 0.0;
  int evaluations_ = 0;
};

// The Hessian of f at x by central differences of its gradient (symmetrised).
Eigen::MatrixXd hessian_by_differences(RewardLogPosterior& f, const Eigen::VectorXd& x);

struct RewardPosterior {
  double prior_scale = 0.0;
  Eigen::VectorXd mode;                // the posterior's mode (MAP)
  Eigen::MatrixXd laplace_covariance;  // the inverse of -Hessian at the mode
  Eigen::MatrixXd samples;             // one draw per row (samples x features)
  Eigen::VectorXd weights;             // their normalised importance weights
  double effective_samples = 0.0;      // 1 / sum w^2: how many equally weighted draws they are worth
  int evaluations = 0;                 // of the log-posterior (each: a soft value iteration and an E-step pass)

  Eigen::VectorXd mean() const;
  // Per feature, the weighted q-quantile of the draws.
  Eigen::VectorXd quantile(double q) const;
  // The posterior probability of an event, given per draw.
  double probability(const std::vector<char>& holds) const;
};

// What the posterior says of a learned reward's optimal policy: the probability that it is
// within `near` of the optimal value (ILE <= near ||V*||_1, metrics.hpp) and that it is
// optimal (ILE 0, to rounding), the expected relative ILE, and per state the probability
// that each action is optimal (where the data leave the task open) -- each over the draws,
// by their weights.
struct PolicyConfidence {
  double near_optimal = 0.0;
  double optimal = 0.0;
  double expected_relative_ile = 0.0;
  Eigen::MatrixXd action_optimal;  // states x actions; 0 at terminal states and impossible actions
};
PolicyConfidence policy_confidence(const Mdp& mdp, const RewardPosterior& posterior,
                                   const Eigen::VectorXd& learned_theta, double near = kNearOptimalShare);

// The confidence under a mixture of two posteriors with weights 1 - w and w (model
// averaging: each number is the mixture's).
PolicyConfidence mix(const PolicyConfidence& a, const PolicyConfidence& b, double w);

// The posterior around EM's theta (`theta_hat`), the E-step in `state` (EM's last).
// Throws InputError for options out of range.
RewardPosterior sample_reward_posterior(const Mdp& mdp, const EStep& estep, const EStepState& state,
                                        const Eigen::VectorXd& theta_hat, const RewardPosteriorOptions& options,
                                        SoftViOptions soft_vi = {});

}  // namespace hbirl
