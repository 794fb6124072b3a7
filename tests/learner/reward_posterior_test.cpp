// The posterior over theta (reward_posterior.hpp) against independent truth: its gradient
// against finite differences, and its mean and quantiles against numerical integration
// over a grid of theta, with the likelihood of the observations by brute-force
// enumeration of every trajectory and labelling.
#include "learner/reward_posterior.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "brute_force_posterior.hpp"
#include "learner/estep_observations.hpp"
#include "learner/input_error.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/value_iteration.hpp"
#include "random_mdp.hpp"
#include "tiny_observed_problem.hpp"

namespace hbirl {
namespace {

using testing::random_distributions;

// A tiny task watched a few times: 3 states, 2 actions, `features` features, 6
// demonstrations of 3 steps, each step seen 1-2 times by a sensor that mistakes one
// confounding element for the subject 30% of the time (eta states it).
struct TinyData {
  Mdp mdp;
  std::vector<Trajectory> truth;
  std::vector<ObservedTrajectory> observed;
  ObservationPrior prior;  // fixed: its mean is the sensor's true model
};

TinyData tiny_data(int features, std::uint64_t seed) {
  Rng rng(seed);
  testing::RandomMdpOptions o;
  o.states = 3;
  o.actions = 2;
  o.features = features;
  o.successors = 2;
  TinyData d{testing::random_mdp(o, rng), {}, {}, {}};
  const Eigen::VectorXd theta = testing::random_vector(features, rng, 1.5);
  const SoftSolution expert = soft_value_iteration(d.mdp, d.mdp.reward(theta));
  const ObservationModel model{random_distributions(d.mdp.num_pairs(), 3, rng), random_distributions(1, 3, rng), {}};
  for (int i = 0; i < 6; ++i) {
    const Trajectory steps = sample_trajectory(d.mdp, expert.policy, 3, rng);
    d.truth.push_back(steps);
    ObservedTrajectory seen;
    std::vector<int> symbols;
    for (const StateAction& x : steps) {
      const int n = 1 + rng.uniform_int(2);
      for (int k = 0; k < n; ++k) {
        const bool subject = rng.uniform() < 0.7;
        const Eigen::VectorXd row = subject ? Eigen::VectorXd(model.subject.row(d.mdp.pair(x.state, x.action)))
                                            : Eigen::VectorXd(model.confounders.row(0));
        symbols.push_back(rng.categorical(row));
      }
      seen.step_begin.push_back(static_cast<int>(symbols.size()));
    }
    seen.symbols = symbols;
    seen.eta = RowMatrix(static_cast<Eigen::Index>(symbols.size()), 2);
    seen.eta.col(0).setConstant(0.7);
    seen.eta.col(1).setConstant(0.3);
    d.observed.push_back(seen);
  }
  d.prior.num_symbols = 3;
  d.prior.num_confounders = 1;
  d.prior.subject_alpha = 100.0 * model.subject;
  d.prior.confounder_alpha = 100.0 * model.confounders;
  d.prior.learn = false;
  d.prior.learn_eta = false;
  return d;
}

// log p(observations | theta) + log N(theta; 0, sigma^2) by enumeration (brute_force_posterior.hpp).
double enumerated_log_posterior(const TinyData& d, const Eigen::VectorXd& theta, double sigma) {
  const SoftSolution policy = soft_value_iteration(d.mdp, d.mdp.reward(theta));
  const ObservationModel model = dirichlet_mean(d.prior);
  double l = 0.0;
  for (const auto& t : d.observed) l += std::log(testing::brute_force(d.mdp, policy, model, t).likelihood);
  return l - 0.5 * theta.squaredNorm() / (sigma * sigma);
}

// sum log pi(a | s) + log N(theta; 0, sigma^2), step by step.
double truth_log_posterior(const TinyData& d, const Eigen::VectorXd& theta, double sigma) {
  const SoftSolution policy = soft_value_iteration(d.mdp, d.mdp.reward(theta));
  double l = 0.0;
  for (const auto& t : d.truth) {
    for (const StateAction& x : t) l += policy.log_policy[d.mdp.pair(x.state, x.action)];
  }
  return l - 0.5 * theta.squaredNorm() / (sigma * sigma);
}

// A posterior on a 1-D grid: its mean, and the q-quantile by the interpolated CDF.
struct GridPosterior {
  std::vector<double> x, p;
  double mean() const {
    double m = 0.0;
    for (size_t i = 0; i < x.size(); ++i) m += x[i] * p[i];
    return m;
  }
  double quantile(double q) const {
    double c = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
      if (c + p[i] >= q) return x[i - (i > 0)] + (x[i] - x[i - (i > 0)]) * (i > 0 ? (q - c) / p[i] : 1.0);
      c += p[i];
    }
    return x.back();
  }
};

template <class LogPosterior>
GridPosterior on_grid(double lo, double hi, int points, LogPosterior&& log_p) {
  GridPosterior g;
  std::vector<double> l;
  for (int i = 0; i < points; ++i) {
    g.x.push_back(lo + (hi - lo) * i / (points - 1));
    l.push_back(log_p(g.x.back()));
  }
  const double top = *std::max_element(l.begin(), l.end());
  double total = 0.0;
  for (double v : l) total += std::exp(v - top);
  for (double v : l) g.p.push_back(std::exp(v - top) / total);
  return g;
}

// The sampler's mean and 5/50/95% quantiles against the grid's, within Monte Carlo error
// (a few of the posterior's standard deviations over the root of the effective samples).
void expect_agrees(const RewardPosterior& post, const GridPosterior& grid, int feature) {
  double var = 0.0;
  const double m = grid.mean();
  for (size_t i = 0; i < grid.x.size(); ++i) var += grid.p[i] * (grid.x[i] - m) * (grid.x[i] - m);
  const double tolerance = 5.0 * std::sqrt(var / post.effective_samples) + 1e-3;
  EXPECT_NEAR(post.mean()[feature], m, tolerance);
  for (double q : {0.05, 0.5, 0.95})
    EXPECT_NEAR(post.quantile(q)[feature], grid.quantile(q), 2.0 * tolerance) << "quantile " << q;
  EXPECT_GT(post.effective_samples, 0.5 * static_cast<double>(post.weights.size()));
}

TEST(RewardPosterior, GradientIsTheLogPosteriorsByFiniteDifferences) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const TinyData d = tiny_data(2, seed);
    const TruthEStep truth(d.mdp, d.truth);
    const ObservationEStep observed(d.mdp, d.observed, d.prior);
    for (const EStep* estep : {static_cast<const EStep*>(&truth), static_cast<const EStep*>(&observed)}) {
      const EStepState state = estep->initial_state(1);
      RewardLogPosterior f(d.mdp, *estep, state, 2.0);
      Rng rng(seed + 100);
      const Eigen::VectorXd theta = testing::random_vector(2, rng, 2.0);
      Eigen::VectorXd g;
      f.evaluate(theta, &g);
      for (int k = 0; k < 2; ++k) {
        const double h = 1e-5;
        Eigen::VectorXd up = theta, down = theta;
        up[k] += h;
        down[k] -= h;
        const double numeric = (f.evaluate(up, nullptr) - f.evaluate(down, nullptr)) / (2 * h);
        EXPECT_NEAR(g[k], numeric, 1e-5 * std::max(1.0, std::abs(numeric))) << "seed " << seed << " feature " << k;
      }
    }
  }
}

// 3000 draws under a given prior scale, around theta = 0 (the mode is found from there).
RewardPosterior drawn(const Mdp& mdp, const EStep& estep, double sigma, std::uint64_t seed) {
  RewardPosteriorOptions o;
  o.samples = 3000;
  o.prior_scale = sigma;
  o.seed = seed;
  return sample_reward_posterior(mdp, estep, estep.initial_state(1), Eigen::VectorXd::Zero(mdp.num_features()), o);
}

TEST(RewardPosterior, OneFeatureFromObservationsAgreesWithEnumerationOnAGrid) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const TinyData d = tiny_data(1, seed);
    const ObservationEStep estep(d.mdp, d.observed, d.prior);
    const double sigma = 2.0;
    const RewardPosterior post = drawn(d.mdp, estep, sigma, seed);
    const GridPosterior grid = on_grid(-12.0, 12.0, 2401, [&](double x) {
      return enumerated_log_posterior(d, Eigen::VectorXd::Constant(1, x), sigma);
    });
    expect_agrees(post, grid, 0);
  }
}

TEST(RewardPosterior, TwoFeaturesFromTrueTrajectoriesAgreeWithAGrid) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const TinyData d = tiny_data(2, seed);
    const TruthEStep estep(d.mdp, d.truth);
    const double sigma = 1.5;
    const RewardPosterior post = drawn(d.mdp, estep, sigma, seed);
    // The 2-D grid's marginals, one feature at a time.
    const int n = 201;
    const double lo = -8.0, hi = 8.0;
    std::vector<double> l(static_cast<size_t>(n * n));
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const Eigen::Vector2d theta(lo + (hi - lo) * i / (n - 1), lo + (hi - lo) * j / (n - 1));
        l[static_cast<size_t>(i * n + j)] = truth_log_posterior(d, theta, sigma);
      }
    }
    const double top = *std::max_element(l.begin(), l.end());
    for (int k = 0; k < 2; ++k) {
      GridPosterior g;
      double total = 0.0;
      for (int i = 0; i < n; ++i) {
        g.x.push_back(lo + (hi - lo) * i / (n - 1));
        double p = 0.0;
        for (int j = 0; j < n; ++j) p += std::exp(l[static_cast<size_t>(k == 0 ? i * n + j : j * n + i)] - top);
        g.p.push_back(p);
        total += p;
      }
      for (double& p : g.p) p /= total;
      expect_agrees(post, g, k);
    }
  }
}

// Per state, some action is optimal under every draw, so the probabilities of a state's
// actions sum to at least 1; the learned policy is optimal only where each of its actions is.
TEST(RewardPosterior, ActionProbabilitiesAgreeWithTheConfidence) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const TinyData d = tiny_data(2, seed);
    const TruthEStep estep(d.mdp, d.truth);
    RewardPosteriorOptions o;
    o.samples = 300;
    o.prior_scale = 2.0;
    const RewardPosterior post =
        sample_reward_posterior(d.mdp, estep, estep.initial_state(1), Eigen::VectorXd::Zero(2), o);
    const PolicyConfidence c = policy_confidence(d.mdp, post, post.mode);
    const OptimalPolicy learned = value_iteration(d.mdp, d.mdp.reward(post.mode));
    EXPECT_LE(c.optimal, c.near_optimal);
    for (int s = 0; s < d.mdp.num_states; ++s) {
      EXPECT_GE(c.action_optimal.row(s).sum(), 1.0 - 1e-9) << "state " << s;
      EXPECT_LE(c.action_optimal.row(s).maxCoeff(), 1.0 + 1e-9);
      EXPECT_LE(c.optimal, c.action_optimal(s, learned.actions[static_cast<size_t>(s)]) + 1e-9) << "state " << s;
    }
  }
}

// (Only that the scale is one of the grid's: the evidence itself is not yet checked against an
// independent computation, docs/MODEL.md.)
TEST(RewardPosterior, TheEvidencesScaleIsOnTheGrid) {
  const TinyData d = tiny_data(2, 5);
  const TruthEStep estep(d.mdp, d.truth);
  RewardPosteriorOptions o;
  o.samples = 50;
  const RewardPosterior post =
      sample_reward_posterior(d.mdp, estep, estep.initial_state(1), Eigen::VectorXd::Zero(2), o);
  const std::vector<double> grid = prior_scale_grid();
  EXPECT_NE(std::find(grid.begin(), grid.end(), post.prior_scale), grid.end());
  EXPECT_TRUE(post.mean().allFinite());
}

TEST(RewardPosterior, OptionsOutOfRangeAreRefused) {
  const TinyData d = tiny_data(1, 1);
  const TruthEStep estep(d.mdp, d.truth);
  RewardPosteriorOptions o;
  o.samples = 0;
  EXPECT_THROW(sample_reward_posterior(d.mdp, estep, estep.initial_state(1), Eigen::VectorXd::Zero(1), o), InputError);
  o.samples = 10;
  o.prior_scale = -1.0;
  EXPECT_THROW(sample_reward_posterior(d.mdp, estep, estep.initial_state(1), Eigen::VectorXd::Zero(1), o), InputError);
}

}  // namespace
}  // namespace hbirl
