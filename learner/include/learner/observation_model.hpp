#pragma once
// The observation model of SPEC §1: the subject's O_{s,a} and each confounding
// element's O_e, categorical over Omega, used as the means of their Dirichlet priors,
// and the refinement of those priors by paper Algorithm 1:
//   alpha_i = c * alpha_dot + (1 - c) * alpha_{i-1}
// where alpha_dot are the expected source-labelled counts from the E-step.
#include "learner/observations.hpp"

namespace hbirl {

struct ObservationModel {
  Eigen::MatrixXd subject;      // (S*A) x Omega, rows sum to 1; column-major so O(., w) is contiguous
  Eigen::MatrixXd confounders;  // E x Omega, rows sum to 1

  int num_symbols() const { return static_cast<int>(subject.cols()); }
  int num_confounders() const { return static_cast<int>(confounders.rows()); }
};

// Expected source-labelled counts (alpha dot): subject(r, w) = E[#observations of symbol w
// made by the subject while at pair r]; confounders(e, w) likewise for element e.
struct AlphaCounts {
  Eigen::MatrixXd subject;
  Eigen::MatrixXd confounders;

  static AlphaCounts zero(int pairs, int confounders, int symbols);
  AlphaCounts& operator+=(const AlphaCounts& other);
};

// Rows normalised: the mean of Dir(alpha) is alpha / sum(alpha). A row whose alpha sums
// to 0 (possible only for pairs the prior leaves empty) becomes uniform.
Eigen::MatrixXd dirichlet_mean(const Eigen::MatrixXd& alpha);
ObservationModel dirichlet_mean(const ObservationPrior& prior);

// alpha <- c * alpha_dot + (1 - c) * alpha, for the subject and the confounders.
void update_alpha(ObservationPrior& prior, const AlphaCounts& alpha_dot, double c);

}  // namespace hbirl
