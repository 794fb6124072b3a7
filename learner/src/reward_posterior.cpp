// The posterior over the reward weights (reward_posterior.hpp).
#include "learner/reward_posterior.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "learner/input_error.hpp"
#include "learner/maxcausalent.hpp"
#include "learner/metrics.hpp"
#include "learner/optimize.hpp"
#include "learner/rng.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl {

namespace {

// 1 / sigma^2; 0 for a flat prior (sigma = inf: the likelihood alone).
double prior_precision(double sigma) { return std::isfinite(sigma) ? 1.0 / (sigma * sigma) : 0.0; }

double standard_normal(Rng& rng) {       // Box-Muller; one of the pair
  const double u = 1.0 - rng.uniform();  // (0, 1]
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * 3.14159265358979323846 * rng.uniform());
}

// The number of visited steps: the log-posterior's scale, for the optimiser's tolerances.
double data_size(const EStep& estep) {
  const std::vector<int> lengths = estep.trajectory_lengths();
  return std::max(1.0, static_cast<double>(std::accumulate(lengths.begin(), lengths.end(), 0)));
}

// A symmetric matrix with its eigenvalues raised to at least `floor`: a curvature the
// proposal can use where the likelihood is flat or (with hidden data) not concave.
Eigen::MatrixXd floored(const Eigen::MatrixXd& m, double floor, Eigen::MatrixXd* inverse_root = nullptr) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m);
  Eigen::VectorXd values = eig.eigenvalues().cwiseMax(floor);
  if (inverse_root) *inverse_root = eig.eigenvectors() * values.cwiseSqrt().cwiseInverse().asDiagonal();
  return eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
}

// The posterior's mode by L-BFGS from `start`, on the log-posterior over the data's size.
Eigen::VectorXd posterior_mode(RewardLogPosterior& f, const Eigen::VectorXd& start, double size) {
  OptimizerOptions o;
  o.gradient_tolerance = 1e-8;
  const Objective objective = [&f, size](const Eigen::VectorXd& x, Eigen::VectorXd& gradient) {
    const double value = f.evaluate(x, &gradient);
    gradient /= size;
    return value / size;
  };
  return maximize_lbfgs(objective, start, o).x;
}

// log p(data | sigma) by the Laplace approximation, for each scale of the grid, from the
// log-likelihood's value, gradient and Hessian at `theta` (a quadratic around EM's
// answer): the scale with the largest.
double scale_by_evidence(const Mdp& mdp, const EStep& estep, const EStepState& state, const Eigen::VectorXd& theta,
                         const SoftViOptions& soft_vi, int& evaluations) {
  RewardLogPosterior likelihood(mdp, estep, state, std::numeric_limits<double>::infinity(), soft_vi);
  Eigen::VectorXd g;
  const double l0 = likelihood.evaluate(theta, &g);
  const Eigen::MatrixXd a = floored(-hessian_by_differences(likelihood, theta), 0.0);
  evaluations += likelihood.evaluations();
  const auto k = static_cast<double>(theta.size());
  double best = -std::numeric_limits<double>::infinity(), chosen = 1.0;
  for (double sigma : prior_scale_grid()) {
    const Eigen::MatrixXd precision =
        a + prior_precision(sigma) * Eigen::MatrixXd::Identity(theta.size(), theta.size());
    const Eigen::LLT<Eigen::MatrixXd> llt(precision);
    if (llt.info() != Eigen::Success) continue;  // (only a curvature that is not a number)
    const Eigen::VectorXd mode = llt.solve(a * theta + g);
    const Eigen::VectorXd d = mode - theta;
    const double l = l0 + g.dot(d) - 0.5 * d.dot(a * d);
    const double log_det = 2.0 * Eigen::MatrixXd(llt.matrixL()).diagonal().array().log().sum();
    const double evidence = l - 0.5 * prior_precision(sigma) * mode.squaredNorm() - k * std::log(sigma) - 0.5 * log_det;
    if (std::isfinite(evidence) && evidence > best) {
      best = evidence;
      chosen = sigma;
    }
  }
  return chosen;
}

// Adds w to every action optimal at each state (within rounding of the value scale, as
// metrics.hpp counts ties).
void add_optimal_actions(const Mdp& mdp, const OptimalPolicy& optimal, double w, Eigen::MatrixXd& out) {
  const double tie = 1e-9 * std::max(1.0, optimal.value.lpNorm<Eigen::Infinity>());
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) continue;
    for (int a = 0; a < mdp.num_actions; ++a) {
      const double q = optimal.q[mdp.pair(s, a)];
      if (std::isfinite(q) && q >= optimal.value[s] - tie) out(s, a) += w;
    }
  }
}

}  // namespace

void check_posterior_options(const RewardPosteriorOptions& o) {
  if (o.samples < 1 || o.samples > 1000000) throw InputError("posterior_samples", "must be in [1, 1000000]");
  if (!(o.prior_scale == 0.0 || (o.prior_scale >= 1e-6 && o.prior_scale <= 1e6)))
    throw InputError("prior_scale", "must be 0 (chosen by the evidence) or in [1e-6, 1e6]");
  if (!(o.student_dof >= 3.0 && o.student_dof <= 100.0) || o.student_dof != std::floor(o.student_dof))
    throw InputError("student_dof", "must be a whole number in [3, 100]");
}

std::vector<double> prior_scale_grid() { return {0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0}; }

RewardLogPosterior::RewardLogPosterior(const Mdp& mdp, const EStep& estep, const EStepState& state, double prior_scale,
                                       SoftViOptions soft_vi)
    : mdp_(mdp), estep_(estep), state_(state), prior_scale_(prior_scale), soft_vi_(soft_vi), solver_(mdp, soft_vi) {
  if (!(prior_scale > 0.0)) throw InputError("prior_scale", "must be > 0");
}

double RewardLogPosterior::evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient) {
  ++evaluations_;
  const SoftSolution& policy = solver_.solve(mdp_.reward(theta));
  const EStepResult e = estep_.fixed_model_statistics(policy, state_);
  log_likelihood_ = e.log_likelihood;
  const double precision = prior_precision(prior_scale_);
  if (gradient) {
    // Fisher's identity: the gradient of log p(data | theta) is that of the expected
    // complete-data log-likelihood sum N_hat log pi_theta at theta itself.
    gradient->setZero(theta.size());
    if (e.counts.sum() > 0.0) {
      CausalLikelihood causal(mdp_, e.counts, 0.0, soft_vi_);
      causal.warm_start(policy);
      causal.evaluate(theta, gradient);
      *gradient *= causal.total_count();
    }
    *gradient -= precision * theta;
  }
  return log_likelihood_ - 0.5 * precision * theta.squaredNorm();
}

Eigen::MatrixXd hessian_by_differences(RewardLogPosterior& f, const Eigen::VectorXd& x) {
  const auto k = x.size();
  Eigen::MatrixXd h(k, k);
  Eigen::VectorXd up, down;
  for (Eigen::Index i = 0; i < k; ++i) {
    const double step = 1e-4 * std::max(1.0, std::abs(x[i]));
    Eigen::VectorXd y = x;
    y[i] = x[i] + step;
    f.evaluate(y, &up);
    y[i] = x[i] - step;
    f.evaluate(y, &down);
    h.col(i) = (up - down) / (2.0 * step);
  }
  return 0.5 * (h + h.transpose());
}

Eigen::VectorXd RewardPosterior::mean() const { return samples.transpose() * weights; }

Eigen::VectorXd RewardPosterior::quantile(double q) const {
  Eigen::VectorXd out(samples.cols());
  std::vector<int> order(static_cast<size_t>(samples.rows()));
  for (Eigen::Index k = 0; k < samples.cols(); ++k) {
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return samples(a, k) < samples(b, k); });
    double cumulative = 0.0;
    out[k] = samples(order.back(), k);
    for (int i : order) {
      cumulative += weights[i];
      if (cumulative >= q) {
        out[k] = samples(i, k);
        break;
      }
    }
  }
  return out;
}

double RewardPosterior::probability(const std::vector<char>& holds) const {
  if (holds.size() != static_cast<size_t>(weights.size())) throw InputError("holds", "one per draw");
  double p = 0.0;
  for (size_t i = 0; i < holds.size(); ++i) p += holds[i] ? weights[static_cast<Eigen::Index>(i)] : 0.0;
  return std::min(p, 1.0);  // the weights sum to 1 only to rounding
}

RewardPosterior sample_reward_posterior(const Mdp& mdp, const EStep& estep, const EStepState& state,
                                        const Eigen::VectorXd& theta_hat, const RewardPosteriorOptions& options,
                                        SoftViOptions soft_vi) {
  check_posterior_options(options);
  RewardPosterior out;
  out.prior_scale = options.prior_scale > 0.0
                        ? options.prior_scale
                        : scale_by_evidence(mdp, estep, state, theta_hat, soft_vi, out.evaluations);
  RewardLogPosterior f(mdp, estep, state, out.prior_scale, soft_vi);
  out.mode = posterior_mode(f, theta_hat, data_size(estep));
  const auto k = theta_hat.size();
  Eigen::MatrixXd root;  // Sigma = root root^T
  const Eigen::MatrixXd hessian = hessian_by_differences(f, out.mode);
  if (!hessian.allFinite() || !out.mode.allFinite()) {
    throw InputError("posterior",
                     "the log-posterior's mode or its curvature is not a number (a likelihood of 0 "
                     "near EM's theta?): no posterior");
  }
  const Eigen::MatrixXd precision = floored(-hessian, prior_precision(out.prior_scale), &root);
  out.laplace_covariance = precision.inverse();
  // Student-t draws: mode + root z sqrt(nu / u), z ~ N(0, I), u ~ chi^2_nu.
  const double nu = options.student_dof;
  Rng rng(options.seed, 0x9057e1u);
  out.samples.resize(options.samples, k);
  Eigen::VectorXd log_w(options.samples);
  for (int i = 0; i < options.samples; ++i) {
    Eigen::VectorXd z(k);
    for (Eigen::Index j = 0; j < k; ++j) z[j] = standard_normal(rng);
    double u = 0.0;
    for (int j = 0; j < static_cast<int>(nu); ++j) u += std::pow(standard_normal(rng), 2);
    const Eigen::VectorXd t = z * std::sqrt(nu / u);
    const Eigen::VectorXd theta = out.mode + root * t;
    out.samples.row(i) = theta.transpose();
    // The proposal's log density up to its constant (the same for every draw).
    const double log_q = -0.5 * (nu + static_cast<double>(k)) * std::log1p(t.squaredNorm() / nu);
    const double log_p = f.evaluate(theta, nullptr);
    log_w[i] = std::isnan(log_p) ? -std::numeric_limits<double>::infinity() : log_p - log_q;
  }
  const double top = log_w.maxCoeff();
  if (!std::isfinite(top)) throw InputError("posterior", "no draw has a positive probability under the data");
  out.weights = (log_w.array() - top).exp();
  out.weights /= out.weights.sum();
  out.effective_samples = 1.0 / out.weights.squaredNorm();
  out.evaluations += f.evaluations();
  return out;
}

PolicyConfidence policy_confidence(const Mdp& mdp, const RewardPosterior& posterior,
                                   const Eigen::VectorXd& learned_theta, double near) {
  PolicyConfidence out;
  out.action_optimal = Eigen::MatrixXd::Zero(mdp.num_states, mdp.num_actions);
  const OptimalPolicy learned = value_iteration(mdp, mdp.reward(learned_theta));
  for (Eigen::Index i = 0; i < posterior.samples.rows(); ++i) {
    const double w = posterior.weights[i];
    if (w == 0.0) continue;
    const Eigen::VectorXd reward = mdp.reward(posterior.samples.row(i).transpose());
    const OptimalPolicy optimal = value_iteration(mdp, reward);
    const double relative = inverse_learning_error(mdp, reward, optimal, learned).relative();
    out.near_optimal += relative <= near ? w : 0.0;
    out.optimal += relative <= 1e-9 ? w : 0.0;
    out.expected_relative_ile += w * relative;
    add_optimal_actions(mdp, optimal, w, out.action_optimal);
  }
  // The weights sum to 1 only to rounding: a probability must not print as 1 + 1e-16.
  out.near_optimal = std::min(out.near_optimal, 1.0);
  out.optimal = std::min(out.optimal, 1.0);
  out.action_optimal = out.action_optimal.cwiseMin(1.0);
  return out;
}

PolicyConfidence mix(const PolicyConfidence& a, const PolicyConfidence& b, double w) {
  PolicyConfidence out;
  out.near_optimal = (1.0 - w) * a.near_optimal + w * b.near_optimal;
  out.optimal = (1.0 - w) * a.optimal + w * b.optimal;
  out.expected_relative_ile = (1.0 - w) * a.expected_relative_ile + w * b.expected_relative_ile;
  out.action_optimal = (1.0 - w) * a.action_optimal + w * b.action_optimal;
  return out;
}

}  // namespace hbirl
