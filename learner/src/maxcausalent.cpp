#include "learner/maxcausalent.hpp"

#include <cmath>
#include <string>

#include "learner/input_error.hpp"

namespace hbirl {

CausalLikelihood::CausalLikelihood(const Mdp& mdp, Eigen::VectorXd counts, double l2, SoftViOptions soft_vi)
    : mdp_(mdp), counts_(std::move(counts)), l2_(l2), solver_(mdp, soft_vi) {
  if (counts_.size() != mdp.num_pairs()) {
    throw InputError("counts",
                     "has " + std::to_string(counts_.size()) + " entries, expected " + std::to_string(mdp.num_pairs()));
  }
  if (!(l2 >= 0.0) || !std::isfinite(l2)) throw InputError("l2", "must be a finite number >= 0");
  state_counts_ = Eigen::VectorXd::Zero(mdp.num_states);
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      const int r = mdp.pair(s, a);
      const double n = counts_[r];
      if (!std::isfinite(n) || n < 0.0) {
        throw InputError("counts", "visit count of (s=" + std::to_string(s) + ", a=" + std::to_string(a) +
                                       ") is not a finite non-negative number");
      }
      if (n == 0.0) continue;
      if (mdp.is_terminal(s) || !mdp.available(s, a)) {
        throw InputError("counts", "visits (s=" + std::to_string(s) + ", a=" + std::to_string(a) +
                                       "), which is impossible or terminal");
      }
      visited_.push_back(r);
      state_counts_[s] += n;
      total_ += n;
    }
  }
  if (!(total_ > 0.0)) throw InputError("counts", "no visited steps");
}

double CausalLikelihood::evaluate(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient) {
  const SoftSolution& sol = solver_.solve(mdp_.reward(theta));
  double ll = 0.0;
  for (int r : visited_) ll += counts_[r] * sol.log_policy[r];
  log_likelihood_ = ll;
  const double objective = ll / total_ - 0.5 * l2_ * theta.squaredNorm();
  if (gradient == nullptr) return objective;

  const int A = mdp_.num_actions;
  // w = N - n * pi, then rho = T^T w restricted to non-terminal next states.
  Eigen::VectorXd w = counts_;
  for (int s = 0; s < mdp_.num_states; ++s) {
    if (state_counts_[s] == 0.0) continue;
    w.segment(static_cast<Eigen::Index>(s) * A, A) -=
        state_counts_[s] * sol.policy.segment(static_cast<Eigen::Index>(s) * A, A);
  }
  Eigen::VectorXd rho = mdp_.transitions.transpose() * w;
  for (int s = 0; s < mdp_.num_states; ++s) {
    if (mdp_.is_terminal(s)) rho[s] = 0.0;
  }
  const Eigen::VectorXd x = solver_.solve_adjoint(rho);
  // w + gamma * x(s) pi(a|s): the total weight each pair's features get in the gradient.
  for (int s = 0; s < mdp_.num_states; ++s) {
    if (mdp_.is_terminal(s)) continue;
    w.segment(static_cast<Eigen::Index>(s) * A, A) +=
        (mdp_.discount * x[s]) * sol.policy.segment(static_cast<Eigen::Index>(s) * A, A);
  }
  gradient->noalias() = mdp_.features.transpose() * w;
  *gradient /= total_;
  *gradient -= l2_ * theta;
  return objective;
}

Eigen::VectorXd empirical_feature_counts(const Mdp& mdp, const Eigen::VectorXd& counts) {
  return mdp.features.transpose() * counts;
}

}  // namespace hbirl
