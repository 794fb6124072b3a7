#pragma once
// The observation model of the paper (§II): the subject's O_{s,a} and each confounding
// element's O_e, categorical over Omega with Dirichlet priors, and how the E-step
// refines those Dirichlets from the expected source-labelled counts alpha_dot (paper
// Algorithm 1). docs/MODEL.md ("The observation model") derives both updates:
//   paper:      alpha_i = c * alpha_dot + (1 - c) * alpha_{i-1}            (fixed point: ML)
//   posterior:  alpha_i = prior(s) + alpha_dot                             (MAP-EM's M-step)
// the second being the Dirichlet posterior, whose mean O is the maximum a posteriori O
// under the prior Dir(prior(s) + 1); prior(s) is the subject's alpha weighed by s and the
// elements' alpha as given. It has no step size, so c never changes its answer.
#include <vector>

#include "learner/observations.hpp"

namespace hbirl {

struct ObservationModel {
  Eigen::MatrixXd subject;      // (S*A) x Omega, rows sum to 1; column-major so O(., w) is contiguous
  Eigen::MatrixXd confounders;  // E x Omega, rows sum to 1
  Eigen::MatrixXd end;          // S x K: the end sensor's O_end(s) (terminal rows used); empty: none

  int num_symbols() const { return static_cast<int>(subject.cols()); }
  int num_confounders() const { return static_cast<int>(confounders.rows()); }
};

// Expected source-labelled counts (alpha dot): subject(r, w) = E[#observations of symbol w
// made by the subject while at pair r]; confounders(e, w) likewise for element e;
// end(s, w) = E[#end symbols w reported of terminal state s] (empty when no trajectory
// summed had any: operator+= takes the other's shape).
struct AlphaCounts {
  Eigen::MatrixXd subject;
  Eigen::MatrixXd confounders;
  Eigen::MatrixXd end;

  static AlphaCounts zero(int pairs, int confounders, int symbols);
  AlphaCounts& operator+=(const AlphaCounts& other);
};

// Rows normalised: the mean of Dir(alpha) is alpha / sum(alpha). A row whose alpha sums
// to 0 (possible only for pairs the prior leaves empty) becomes uniform.
Eigen::MatrixXd dirichlet_mean(const Eigen::MatrixXd& alpha);
ObservationModel dirichlet_mean(const ObservationPrior& prior);

// Per (s, a) row of the subject's prior: whether the prior has counts for it (an entry above
// subject_alpha_base). weighed_subject_prior weighs those by the strength and holds the
// others at the prior's mean (docs/MODEL.md, "The observation model").
Eigen::Array<bool, Eigen::Dynamic, 1> counted_subject_pairs(const ObservationPrior& prior);

// Ties the subject's prior across each state's actions (docs/MODEL.md "A state's actions
// share their view"): sets prior.subject_base_shape so that row (s, a)'s base has the
// mean rho * m_{s,-a} + (1 - rho) * uniform, m_{s,-a} the normalised counts (above the
// base) of the state's *other* actions, and prior.subject_tie = rho (exactly so where every
// entry of the row is at least the base; an entry below it keeps its share of the shape,
// min(alpha, base) * shape). rho is chosen on k / 20, k = 0 .. 19, by the
// Dirichlet-multinomial likelihood of each counted row's counts under the base its state's
// other rows give it (one action left out at a time; rows with at least one observation's
// worth of counts whose siblings have as much): what the controlled run itself says of how
// much a state's actions share. rho = 0 (no state with two such actions -- a controlled run
// that takes one action per state -- or a sensor whose actions share nothing) leaves the
// shape empty, so the prior is the flat base, bit for bit. Rows are s * num_actions + a.
void tie_subject_prior_across_actions(ObservationPrior& prior, int num_actions);
// Whether the tie applies: asked for (tie_actions) and the posterior update (the paper's
// update has no base to shape). ObservationEStep ties the prior when it does; what prints
// the share asks the same.
inline bool ties_subject_prior(const ObservationPrior& prior) {
  return prior.tie_actions && prior.update == AlphaUpdate::kPosterior;
}

// The subject's power prior at strength s: min(alpha, base) + s * max(alpha - base, 0)
// (ObservationPrior).
Eigen::MatrixXd weighed_subject_prior(const ObservationPrior& prior, double s);

// The end sensor's prior as the posterior update uses it: end_alpha, with the rows of
// terminal states it has no counts for (no entry above end_alpha_base) held at their
// mean (times kMaxStrength), unless no row has counts.
Eigen::MatrixXd weighed_end_prior(const ObservationPrior& prior);

// The Dirichlet posterior of the posterior update for prior `prior`, subject weight s and
// expected counts: weighed_subject_prior(prior, s) + counts.subject, prior.confounder_alpha
// + counts.confounders, weighed_end_prior(prior) + counts.end.
AlphaCounts dirichlet_posterior(const ObservationPrior& prior, double s, const AlphaCounts& counts);

// The mean O of the posterior update without one trajectory (docs/MODEL.md, "How much the
// controlled run weighs"): dirichlet_posterior(prior, s, others) with others = all - own,
// clipped at 0, `all` the expected counts of every trajectory and `own` that trajectory's,
// both under the same O. What the prior strength is chosen by, and what a cross-fitted
// E-step computes each trajectory under.
ObservationModel leave_one_out_mean(const ObservationPrior& prior, double s, const AlphaCounts& all,
                                    const AlphaCounts& own);

// The prior's term of the posterior update's objective (MAP-EM maximises log Pr(data |
// theta, O) plus this): sum over entries of beta * log(O / O_prior) with beta the weighed
// prior and O_prior its mean (entries with beta 0 left out), i.e. log Dir(O; beta + 1) up
// to a constant. 0 for the paper's update and for a fixed model.
double log_prior_term(const ObservationModel& model, const ObservationPrior& prior, const ObservationPrior& alpha);

// The strengths the posterior update chooses from: 10^(k/2), k = -6 .. 6 (1e-3 .. 1e3).
const std::vector<double>& prior_strength_grid();

// One refinement of `alpha` (the current parameters) by the rule in alpha.update, from the
// E-step's alpha_dot; `prior` is the model's Dirichlet prior. kPosterior: the exact M-step,
// alpha = weighed prior + alpha_dot (c is not used); kPaper: c alpha_dot + (1 - c) alpha.
void update_alpha(ObservationPrior& alpha, const ObservationPrior& prior, const AlphaCounts& alpha_dot);

}  // namespace hbirl
