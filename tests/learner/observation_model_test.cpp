#include "learner/observation_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "learner/rng.hpp"

namespace hbirl {
namespace {

TEST(ObservationModel, DirichletMean) {
  Eigen::MatrixXd alpha(2, 3);
  alpha << 1, 2, 7, 0, 0, 0;
  const Eigen::MatrixXd mean = dirichlet_mean(alpha);
  EXPECT_DOUBLE_EQ(mean(0, 0), 0.1);
  EXPECT_DOUBLE_EQ(mean(0, 2), 0.7);
  EXPECT_DOUBLE_EQ(mean(1, 1), 1.0 / 3);  // empty prior: uniform
}

// One pair and one element over two symbols: subject alpha (4, 6), element alpha (1, 1),
// c = 0.25; one refinement from alpha_dot = (10, 0) and (2, 6).
ObservationPrior refined_by_hand(AlphaUpdate update, double strength) {
  ObservationPrior prior;
  prior.num_symbols = 2;
  prior.num_confounders = 1;
  prior.update = update;
  prior.c = 0.25;
  prior.automatic_strength = false;
  prior.strength = strength;
  prior.subject_alpha = Eigen::MatrixXd(1, 2);
  prior.subject_alpha << 4, 6;
  prior.confounder_alpha = Eigen::MatrixXd(1, 2);
  prior.confounder_alpha << 1, 1;
  AlphaCounts dot = AlphaCounts::zero(1, 1, 2);
  dot.subject << 10, 0;
  dot.confounders << 2, 6;
  ObservationPrior alpha = prior;
  update_alpha(alpha, prior, dot);
  return alpha;
}

// The paper's update: alpha' = 0.25 (10, 0) + 0.75 (4, 6) = (5.5, 4.5), mean (0.55, 0.45);
// element 0.25 (2, 6) + 0.75 (1, 1) = (1.25, 2.25).
TEST(ObservationModel, PaperUpdateByHand) {
  const ObservationPrior alpha = refined_by_hand(AlphaUpdate::kPaper, 1.0);
  EXPECT_DOUBLE_EQ(alpha.subject_alpha(0, 0), 5.5);
  EXPECT_DOUBLE_EQ(alpha.subject_alpha(0, 1), 4.5);
  EXPECT_DOUBLE_EQ(alpha.confounder_alpha(0, 0), 1.25);
  EXPECT_DOUBLE_EQ(alpha.confounder_alpha(0, 1), 2.25);
  const ObservationModel model = dirichlet_mean(alpha);
  EXPECT_DOUBLE_EQ(model.subject(0, 0), 0.55);
  EXPECT_DOUBLE_EQ(model.confounders(0, 1), 2.25 / 3.5);
}

// The posterior update with strength s = 2 and base 1: subject prior(2) = 1 + 2 (3, 5) =
// (7, 11), alpha' = (7, 11) + (10, 0) = (17, 11) at once (the exact M-step; c = 0.25 is
// not used); elements (their prior as given) (1, 1) + (2, 6) = (3, 7).
TEST(ObservationModel, PosteriorUpdateByHand) {
  const ObservationPrior alpha = refined_by_hand(AlphaUpdate::kPosterior, 2.0);
  EXPECT_DOUBLE_EQ(alpha.subject_alpha(0, 0), 17.0);
  EXPECT_DOUBLE_EQ(alpha.subject_alpha(0, 1), 11.0);
  EXPECT_DOUBLE_EQ(alpha.confounder_alpha(0, 0), 3.0);
  EXPECT_DOUBLE_EQ(alpha.confounder_alpha(0, 1), 7.0);
}

ObservationPrior random_prior(Rng& rng) {
  ObservationPrior prior;
  prior.num_symbols = 3;
  prior.num_confounders = 2;
  prior.subject_alpha = Eigen::MatrixXd(4, 3);
  prior.confounder_alpha = Eigen::MatrixXd(2, 3);
  for (Eigen::Index i = 0; i < prior.subject_alpha.size(); ++i) prior.subject_alpha.data()[i] = 0.5 + 5 * rng.uniform();
  for (Eigen::Index i = 0; i < prior.confounder_alpha.size(); ++i)
    prior.confounder_alpha.data()[i] = 0.5 + rng.uniform();
  return prior;
}

// With no data the posterior update returns the prior, and with data prior + alpha_dot,
// in one step and whatever c is (c is the paper's step size only). The weighed prior
// keeps the base and scales what is above it.
TEST(ObservationModel, PosteriorUpdateReturnsPriorPlusCountsWhateverC) {
  Rng rng(5);
  const ObservationPrior prior = random_prior(rng);
  const AlphaCounts none = AlphaCounts::zero(4, 2, 3);
  AlphaCounts dot = none;
  for (Eigen::Index i = 0; i < dot.subject.size(); ++i) dot.subject.data()[i] = 10 * rng.uniform();
  for (Eigen::Index i = 0; i < dot.confounders.size(); ++i) dot.confounders.data()[i] = 30 * rng.uniform();
  for (double s : {1.0, 0.01, 30.0}) {
    const Eigen::MatrixXd weighed = weighed_subject_prior(prior, s);
    Eigen::MatrixXd by_hand = prior.subject_alpha;
    for (Eigen::Index i = 0; i < by_hand.size(); ++i) {
      const double a = prior.subject_alpha.data()[i];
      by_hand.data()[i] = a <= 1.0 ? a : 1.0 + s * (a - 1.0);
    }
    EXPECT_LT((weighed - by_hand).cwiseAbs().maxCoeff(), 1e-12);
    if (s == 1.0) {
      EXPECT_EQ(weighed, prior.subject_alpha);
    }
    for (double c : {1.0, 0.5, 0.1, 0.02}) {
      ObservationPrior alpha = prior;
      alpha.c = c;
      alpha.strength = s;
      alpha.subject_alpha.setConstant(123.0);  // wherever the previous iteration left it
      update_alpha(alpha, prior, none);
      EXPECT_LT((alpha.subject_alpha - weighed).cwiseAbs().maxCoeff(), 1e-12) << "c = " << c;
      EXPECT_LT((alpha.confounder_alpha - prior.confounder_alpha).cwiseAbs().maxCoeff(), 1e-12) << "c = " << c;
      update_alpha(alpha, prior, dot);
      EXPECT_LT((alpha.subject_alpha - (weighed + dot.subject)).cwiseAbs().maxCoeff(), 1e-12) << "c = " << c;
      EXPECT_LT((alpha.confounder_alpha - (prior.confounder_alpha + dot.confounders)).cwiseAbs().maxCoeff(), 1e-12)
          << "c = " << c;
    }
  }
}

// The paper's update forgets the prior: its fixed point is alpha_dot.
TEST(ObservationModel, PaperUpdateForgetsThePrior) {
  ObservationPrior prior;
  prior.num_symbols = 2;
  prior.num_confounders = 0;
  prior.update = AlphaUpdate::kPaper;
  prior.c = 0.1;
  prior.subject_alpha = Eigen::MatrixXd::Constant(1, 2, 50.0);
  prior.confounder_alpha = Eigen::MatrixXd::Zero(0, 2);
  AlphaCounts dot = AlphaCounts::zero(1, 0, 2);
  dot.subject << 3, 1;
  ObservationPrior alpha = prior;
  for (int i = 0; i < 1000; ++i) update_alpha(alpha, prior, dot);
  EXPECT_NEAR(alpha.subject_alpha(0, 0), 3.0, 1e-9);
  EXPECT_NEAR(alpha.subject_alpha(0, 1), 1.0, 1e-9);
}

// MAP-EM's M-step (docs/MODEL.md): the mean of the Dirichlet posterior, O = (s alpha + n) /
// sum, maximises sum_w n_w log O_w (the expected complete-data log-likelihood) plus the
// prior's term sum_w s alpha_w log O_w over the simplex. Checked against random
// perturbations of it, and the term against its definition.
TEST(ObservationModel, PosteriorMeanMaximisesTheMapObjective) {
  Rng rng(21);
  const ObservationPrior prior = random_prior(rng);
  ObservationPrior alpha = prior;
  alpha.strength = 2.5;
  AlphaCounts dot = AlphaCounts::zero(4, 2, 3);
  for (Eigen::Index i = 0; i < dot.subject.size(); ++i) dot.subject.data()[i] = 10 * rng.uniform();
  for (Eigen::Index i = 0; i < dot.confounders.size(); ++i) dot.confounders.data()[i] = 30 * rng.uniform();
  const AlphaCounts posterior = dirichlet_posterior(prior, alpha.strength, dot);
  const ObservationModel best{dirichlet_mean(posterior.subject), dirichlet_mean(posterior.confounders), {}};
  auto objective = [&](const ObservationModel& o) {
    double f = 0.0;
    for (Eigen::Index i = 0; i < o.subject.size(); ++i) f += dot.subject.data()[i] * std::log(o.subject.data()[i]);
    for (Eigen::Index i = 0; i < o.confounders.size(); ++i)
      f += dot.confounders.data()[i] * std::log(o.confounders.data()[i]);
    return f + log_prior_term(o, prior, alpha);
  };
  // By hand: beta log(O / mean of beta), beta = 1 + 2.5 (alpha - 1) above the base.
  Eigen::MatrixXd beta = prior.subject_alpha;
  for (Eigen::Index i = 0; i < beta.size(); ++i) {
    const double a = prior.subject_alpha.data()[i];
    beta.data()[i] = a <= 1.0 ? a : 1.0 + 2.5 * (a - 1.0);
  }
  const Eigen::MatrixXd beta_mean = dirichlet_mean(beta);
  const Eigen::MatrixXd element_mean = dirichlet_mean(prior.confounder_alpha);
  double by_hand = 0.0;
  for (Eigen::Index i = 0; i < best.subject.size(); ++i) {
    by_hand += beta.data()[i] * std::log(best.subject.data()[i] / beta_mean.data()[i]);
  }
  for (Eigen::Index i = 0; i < best.confounders.size(); ++i) {
    by_hand += prior.confounder_alpha.data()[i] * std::log(best.confounders.data()[i] / element_mean.data()[i]);
  }
  EXPECT_NEAR(log_prior_term(best, prior, alpha), by_hand, 1e-9 * std::abs(by_hand));
  const double at_best = objective(best);
  for (int trial = 0; trial < 200; ++trial) {
    ObservationModel other = best;
    for (Eigen::Index i = 0; i < other.subject.size(); ++i)
      other.subject.data()[i] *= std::exp(0.1 * (rng.uniform() - 0.5));
    for (Eigen::Index i = 0; i < other.confounders.size(); ++i)
      other.confounders.data()[i] *= std::exp(0.1 * (rng.uniform() - 0.5));
    other.subject = dirichlet_mean(other.subject);
    other.confounders = dirichlet_mean(other.confounders);
    EXPECT_LE(objective(other), at_best + 1e-9);
  }
  // The paper's update and a fixed model have no prior term.
  ObservationPrior paper = alpha;
  paper.update = AlphaUpdate::kPaper;
  EXPECT_EQ(log_prior_term(best, prior, paper), 0.0);
}

TEST(ObservationModel, StrengthGridSpansThreeDecadesEachWay) {
  const std::vector<double>& grid = prior_strength_grid();
  ASSERT_EQ(grid.size(), 13u);
  EXPECT_NEAR(grid.front(), ObservationPrior::kMinStrength, 1e-15);
  EXPECT_NEAR(grid.back(), ObservationPrior::kMaxStrength, 1e-9);
  EXPECT_EQ(grid[6], 1.0);  // the prior as written is on the grid
}

// A controlled run of `visits` observations per counted (s, a) of a sensor whose rows are
// share * (the state's row) + (1 - share) * (the action's own row); pairs with a = A - 1
// never visited; S states. Base 1 per symbol.
ObservationPrior shared_view_prior(double share, int visits, std::uint64_t seed, int S = 6) {
  const int A = 3, W = 8;
  Rng rng(seed);
  auto random_row = [&] {
    Eigen::VectorXd row(W);
    for (int w = 0; w < W; ++w) row[w] = std::pow(rng.uniform(), 4.0);  // peaked
    return Eigen::VectorXd(row / row.sum());
  };
  ObservationPrior prior;
  prior.num_symbols = W;
  prior.subject_alpha = Eigen::MatrixXd::Ones(S * A, W);
  for (int s = 0; s < S; ++s) {
    const Eigen::VectorXd state = random_row();
    for (int a = 0; a + 1 < A; ++a) {
      const Eigen::VectorXd o = share * state + (1.0 - share) * random_row();
      for (int n = 0; n < visits; ++n) prior.subject_alpha(s * A + a, rng.categorical(o)) += 1.0;
    }
  }
  return prior;
}

// log Pr(a sequence with these counts | Dir(beta)) by the Polya urn, one draw at a time:
// an independent route to the lgamma form the share is chosen by.
double polya_urn_log(const Eigen::RowVectorXd& counts, const Eigen::RowVectorXd& beta) {
  Eigen::RowVectorXd urn = beta;
  double sum = 0.0;
  for (Eigen::Index w = 0; w < counts.size(); ++w) {
    for (int n = 0; n < static_cast<int>(counts[w]); ++n) {
      sum += std::log(urn[w] / urn.sum());
      urn[w] += 1.0;
    }
  }
  return sum;
}

TEST(ObservationModel, TieChoosesTheShareThatBestPredictsEachActionFromItsSiblings) {
  const int A = 3;
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    ObservationPrior prior = shared_view_prior(0.8, 12, seed);
    tie_subject_prior_across_actions(prior, A);
    // The brute-force choice: each counted row's urn likelihood under the base its state's
    // other counted rows give it, at every share on the grid.
    const Eigen::MatrixXd counts = (prior.subject_alpha.array() - 1.0).max(0.0);
    double best = -INFINITY, best_rho = -1.0;
    for (int k = 0; k < 20; ++k) {
      const double rho = k / 20.0;
      double score = 0.0;
      for (int s = 0; s < counts.rows() / A; ++s) {
        for (int a = 0; a < A; ++a) {
          Eigen::RowVectorXd others = Eigen::RowVectorXd::Zero(counts.cols());
          for (int b = 0; b < A; ++b)
            if (b != a) others += counts.row(s * A + b);
          if (counts.row(s * A + a).sum() == 0.0 || others.sum() == 0.0) continue;
          const double W = static_cast<double>(counts.cols());
          const Eigen::RowVectorXd mean =
              rho * others / others.sum() + Eigen::RowVectorXd::Constant(counts.cols(), (1.0 - rho) / W);
          score += polya_urn_log(counts.row(s * A + a), mean * W);
        }
      }
      if (score > best + 1e-9) {
        best = score;
        best_rho = rho;
      }
    }
    EXPECT_DOUBLE_EQ(prior.subject_tie, best_rho) << "seed " << seed;
    EXPECT_GT(prior.subject_tie, 0.3) << "seed " << seed;  // these actions share 80% of their view
  }
}

TEST(ObservationModel, TieIsOffWhenActionsShareNothing) {
  int tied = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    ObservationPrior prior = shared_view_prior(0.0, 200, seed, 40);
    const Eigen::MatrixXd flat = weighed_subject_prior(prior, 0.5);
    tie_subject_prior_across_actions(prior, 3);
    EXPECT_LE(prior.subject_tie, 0.1) << "seed " << seed;
    if (prior.subject_tie == 0.0) {
      ++tied;
      EXPECT_EQ(prior.subject_base_shape.size(), 0);
      EXPECT_EQ(weighed_subject_prior(prior, 0.5), flat);  // bit for bit: the flat base
    }
  }
  EXPECT_GE(tied, 7);
}

TEST(ObservationModel, TiedPriorHoldsAnUnseenActionAtItsStatesView) {
  const int A = 3;
  ObservationPrior prior = shared_view_prior(1.0, 40, 7);
  tie_subject_prior_across_actions(prior, A);
  ASSERT_GT(prior.subject_tie, 0.5);
  const double rho = prior.subject_tie;
  const Eigen::MatrixXd weighed = weighed_subject_prior(prior, 0.3);
  const Eigen::MatrixXd counts = (prior.subject_alpha.array() - 1.0).max(0.0);
  const double W = static_cast<double>(counts.cols());
  for (int s = 0; s < counts.rows() / A; ++s) {
    // Row a = A - 1 was never visited: held (1000 x the base) at rho * the state's pooled
    // view + (1 - rho) * uniform.
    const Eigen::RowVectorXd pooled = counts.row(s * A) + counts.row(s * A + 1);
    const Eigen::RowVectorXd mean =
        rho * pooled / pooled.sum() + Eigen::RowVectorXd::Constant(counts.cols(), (1.0 - rho) / W);
    const Eigen::RowVectorXd unseen = weighed.row(s * A + A - 1);
    EXPECT_NEAR(unseen.sum(), ObservationPrior::kMaxStrength * W, 1e-6);
    EXPECT_LT((unseen / unseen.sum() - mean).cwiseAbs().maxCoeff(), 1e-12);
    // A counted row: its sibling's view as the base's shape (mean 1), its own counts weighed.
    const Eigen::RowVectorXd sibling = counts.row(s * A + 1);
    const Eigen::RowVectorXd base = (rho * W / sibling.sum()) * sibling.array() + (1.0 - rho);
    EXPECT_LT((weighed.row(s * A) - (base + 0.3 * counts.row(s * A))).cwiseAbs().maxCoeff(), 1e-12);
  }
}

// Siblings whose view is uniform say nothing: every share scores the same, and a tie keeps
// the smaller share, 0 (no shape). A share chosen from a few hundredths of an observation
// would hold every unseen pair; rows need one observation's worth to be scored.
TEST(ObservationModel, TieNeedsEvidence) {
  ObservationPrior uniform;
  uniform.subject_alpha = Eigen::MatrixXd::Constant(4, 3, 3.0);  // two states, two actions, 2 counts per symbol
  tie_subject_prior_across_actions(uniform, 2);
  EXPECT_EQ(uniform.subject_tie, 0.0);
  EXPECT_EQ(uniform.subject_base_shape.size(), 0);
  ObservationPrior faint;
  faint.subject_alpha = Eigen::MatrixXd::Ones(4, 3);
  faint.subject_alpha(0, 1) += 0.05;  // state 0: both actions on symbol 1, a twentieth of a count each
  faint.subject_alpha(1, 1) += 0.04;
  tie_subject_prior_across_actions(faint, 2);
  EXPECT_EQ(faint.subject_tie, 0.0);
  faint.subject_alpha(0, 1) += 1.0;  // one observation each: now they count, and they agree
  faint.subject_alpha(1, 1) += 1.0;
  tie_subject_prior_across_actions(faint, 2);
  EXPECT_GT(faint.subject_tie, 0.0);
  EXPECT_GE(faint.subject_base_shape.minCoeff(), 0.05 - 1e-12);  // rho <= 0.95: no structural zeros
}

// A row with entries below the base (a problem file may give them) keeps them as its base,
// times the shape: min(alpha, base) * shape + s * counts, checked entry by entry.
TEST(ObservationModel, TiedBaseOfEntriesBelowTheBase) {
  ObservationPrior prior = shared_view_prior(0.9, 30, 11);
  prior.subject_alpha(2, 0) = 0.25;  // state 0's never-visited action (row 2): entries below the base
  prior.subject_alpha(2, 3) = 0.0;
  tie_subject_prior_across_actions(prior, 3);
  ASSERT_GT(prior.subject_tie, 0.0);
  const Eigen::MatrixXd weighed = weighed_subject_prior(prior, 2.0);
  for (Eigen::Index r = 0; r < 3; ++r) {
    for (Eigen::Index w = 0; w < prior.subject_alpha.cols(); ++w) {
      const double alpha = prior.subject_alpha(r, w);
      const double base = std::min(alpha, 1.0) * prior.subject_base_shape(r, w);
      const double expected = r == 2 ? ObservationPrior::kMaxStrength * base : base + 2.0 * std::max(alpha - 1.0, 0.0);
      EXPECT_DOUBLE_EQ(weighed(r, w), expected) << r << "," << w;
    }
  }
  EXPECT_EQ(weighed(2, 3), 0.0);  // a zero stays a zero
}

TEST(ObservationModel, TieNeedsAStateWithTwoCountedActions) {
  ObservationPrior prior;
  prior.subject_alpha = Eigen::MatrixXd::Ones(4, 3);
  prior.subject_alpha(0, 1) = 5.0;  // state 0, action 0 only
  prior.subject_alpha(3, 2) = 5.0;  // state 1, action 1 only
  tie_subject_prior_across_actions(prior, 2);
  EXPECT_EQ(prior.subject_tie, 0.0);
  EXPECT_EQ(prior.subject_base_shape.size(), 0);
  tie_subject_prior_across_actions(prior, 3);  // 4 rows are not whole states of 3 actions
  EXPECT_EQ(prior.subject_base_shape.size(), 0);
}

}  // namespace
}  // namespace hbirl
