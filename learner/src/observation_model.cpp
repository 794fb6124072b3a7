#include "learner/observation_model.hpp"

namespace hbirl {

AlphaCounts AlphaCounts::zero(int pairs, int confounders, int symbols) {
  return {Eigen::MatrixXd::Zero(pairs, symbols), Eigen::MatrixXd::Zero(confounders, symbols)};
}

AlphaCounts& AlphaCounts::operator+=(const AlphaCounts& other) {
  subject += other.subject;
  confounders += other.confounders;
  return *this;
}

Eigen::MatrixXd dirichlet_mean(const Eigen::MatrixXd& alpha) {
  Eigen::MatrixXd mean(alpha.rows(), alpha.cols());
  for (Eigen::Index r = 0; r < alpha.rows(); ++r) {
    const double total = alpha.row(r).sum();
    if (total > 0.0) {
      mean.row(r) = alpha.row(r) / total;
    } else {
      mean.row(r).setConstant(1.0 / static_cast<double>(alpha.cols()));
    }
  }
  return mean;
}

ObservationModel dirichlet_mean(const ObservationPrior& prior) {
  return {dirichlet_mean(prior.subject_alpha), dirichlet_mean(prior.confounder_alpha)};
}

void update_alpha(ObservationPrior& prior, const AlphaCounts& alpha_dot, double c) {
  prior.subject_alpha = c * alpha_dot.subject + (1.0 - c) * prior.subject_alpha;
  prior.confounder_alpha = c * alpha_dot.confounders + (1.0 - c) * prior.confounder_alpha;
}

}  // namespace hbirl
