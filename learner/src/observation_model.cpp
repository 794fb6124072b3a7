#include "learner/observation_model.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "learner/input_error.hpp"

namespace hbirl {

AlphaCounts AlphaCounts::zero(int pairs, int confounders, int symbols) {
  return {Eigen::MatrixXd::Zero(pairs, symbols), Eigen::MatrixXd::Zero(confounders, symbols), Eigen::MatrixXd()};
}

AlphaCounts& AlphaCounts::operator+=(const AlphaCounts& other) {
  subject += other.subject;
  confounders += other.confounders;
  if (end.size() == 0) {
    end = other.end;
  } else if (other.end.size() > 0) {
    end += other.end;
  }
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
  return {dirichlet_mean(prior.subject_alpha), dirichlet_mean(prior.confounder_alpha), dirichlet_mean(prior.end_alpha)};
}

Eigen::Array<bool, Eigen::Dynamic, 1> counted_subject_pairs(const ObservationPrior& prior) {
  return (prior.subject_alpha.array() > prior.subject_alpha_base).rowwise().any();
}

Eigen::MatrixXd weighed_subject_prior(const ObservationPrior& prior, double s) {
  const double base = prior.subject_alpha_base;
  const auto counts = (prior.subject_alpha.array() - base).max(0.0);
  if (prior.subject_base_shape.size() > 0 && (prior.subject_base_shape.rows() != prior.subject_alpha.rows() ||
                                              prior.subject_base_shape.cols() != prior.subject_alpha.cols()))
    throw InputError("observation_model.subject_base_shape", "is not the shape of subject_alpha");
  Eigen::MatrixXd out =
      prior.subject_base_shape.size() == 0
          ? Eigen::MatrixXd(prior.subject_alpha.array().min(base) + s * counts)
          : Eigen::MatrixXd(prior.subject_alpha.array().min(base) * prior.subject_base_shape.array() + s * counts);
  // Pairs the prior has no counts for keep its mean (docs/MODEL.md, "The observation
  // model"): a pair whose O the demonstration alone could set would explain observations
  // by the expert doing what it did not do. Unless no pair has counts (no controlled run:
  // then O can only come from the demonstration).
  const Eigen::Array<bool, Eigen::Dynamic, 1> counted = counted_subject_pairs(prior);
  if (counted.any()) {
    for (Eigen::Index r = 0; r < out.rows(); ++r) {
      if (!counted[r]) out.row(r) *= ObservationPrior::kMaxStrength;
    }
  }
  return out;
}

namespace {
// log Pr(counts | Dir(beta)) for one multinomial row, up to the counts' multinomial
// coefficient (the same for every beta): the lgamma form, so counts may be fractional
// (a per-visit controlled run).
double log_dirichlet_multinomial(const Eigen::RowVectorXd& counts, const Eigen::RowVectorXd& beta) {
  // lgamma_r: std::lgamma writes glibc's global signgam, a data race between E-steps built
  // on several threads (the values are the same).
  auto log_gamma = [](double x) {
    int sign = 0;
    return lgamma_r(x, &sign);
  };
  double sum = log_gamma(beta.sum()) - log_gamma(beta.sum() + counts.sum());
  for (Eigen::Index w = 0; w < counts.size(); ++w) {
    if (counts[w] > 0.0) sum += log_gamma(beta[w] + counts[w]) - log_gamma(beta[w]);
  }
  return sum;
}

// Row r's base shape at share rho: W * (rho * m + (1 - rho) / W), m = others / sum(others),
// its mean 1; the flat base (1s) where the state's other actions have no counts.
Eigen::RowVectorXd base_shape(const Eigen::RowVectorXd& others, double rho) {
  const double total = others.sum();
  if (total <= 0.0) return Eigen::RowVectorXd::Ones(others.size());
  return (rho * static_cast<double>(others.size()) / total) * others.array() + (1.0 - rho);
}
}  // namespace

void tie_subject_prior_across_actions(ObservationPrior& prior, int num_actions) {
  prior.subject_base_shape.resize(0, 0);
  prior.subject_tie = 0.0;
  const Eigen::Index P = prior.subject_alpha.rows();
  if (num_actions < 2 || P % num_actions != 0) return;
  const double base = prior.subject_alpha_base;
  const Eigen::MatrixXd counts = (prior.subject_alpha.array() - base).max(0.0);
  const Eigen::MatrixXd flat = prior.subject_alpha.array().min(base);
  // others.row(r): the counts of r's state's other actions.
  Eigen::MatrixXd others(P, counts.cols());
  for (Eigen::Index first = 0; first < P; first += num_actions) {
    const Eigen::RowVectorXd state = counts.middleRows(first, num_actions).colwise().sum();
    for (Eigen::Index r = first; r < first + num_actions; ++r) others.row(r) = state - counts.row(r);
  }
  // Scored: rows with at least one observation's worth of counts whose state's other
  // actions have as much (a few hundredths of an observation must not set the share that
  // holds every unseen pair).
  std::vector<Eigen::Index> scored;
  for (Eigen::Index r = 0; r < P; ++r) {
    if (counts.row(r).sum() >= 1.0 && others.row(r).sum() >= 1.0) scored.push_back(r);
  }
  if (scored.empty()) return;
  double best_rho = 0.0;
  double best = -std::numeric_limits<double>::infinity();
  for (int k = 0; k < 20; ++k) {
    const double rho = k / 20.0;
    double score = 0.0;
    for (Eigen::Index r : scored) {
      const Eigen::RowVectorXd beta = flat.row(r).array() * base_shape(others.row(r), rho).array();
      score += log_dirichlet_multinomial(counts.row(r), beta);
    }
    if (score > best) {  // ties keep the smaller share
      best = score;
      best_rho = rho;
    }
  }
  if (best_rho == 0.0) return;
  prior.subject_base_shape.resize(P, counts.cols());
  for (Eigen::Index r = 0; r < P; ++r) prior.subject_base_shape.row(r) = base_shape(others.row(r), best_rho);
  prior.subject_tie = best_rho;
}

Eigen::MatrixXd weighed_end_prior(const ObservationPrior& prior) {
  Eigen::MatrixXd out = prior.end_alpha;
  // As for the subject's pairs (weighed_subject_prior): a terminal state the prior has no
  // counts for keeps its mean, or the demonstration alone would set what the sensor says
  // of it and could explain reports by the expert entering where it did not.
  const Eigen::Array<bool, Eigen::Dynamic, 1> counted =
      (prior.end_alpha.array() > prior.end_alpha_base).rowwise().any();
  if (counted.any()) {
    for (Eigen::Index s = 0; s < out.rows(); ++s) {
      if (!counted[s]) out.row(s) *= ObservationPrior::kMaxStrength;
    }
  }
  return out;
}

namespace {
// The end sensor's weighed prior plus its expected counts (none summed yet: the prior's).
Eigen::MatrixXd end_posterior(const ObservationPrior& prior, const AlphaCounts& counts) {
  Eigen::MatrixXd out = weighed_end_prior(prior);
  if (counts.end.size() > 0) out += counts.end;
  return out;
}
}  // namespace

AlphaCounts dirichlet_posterior(const ObservationPrior& prior, double s, const AlphaCounts& counts) {
  return {weighed_subject_prior(prior, s) + counts.subject, prior.confounder_alpha + counts.confounders,
          end_posterior(prior, counts)};
}

ObservationModel leave_one_out_mean(const ObservationPrior& prior, double s, const AlphaCounts& all,
                                    const AlphaCounts& own) {
  AlphaCounts others = all;
  others.subject = (others.subject - own.subject).cwiseMax(0.0);
  others.confounders = (others.confounders - own.confounders).cwiseMax(0.0);
  if (own.end.size() > 0) others.end = (others.end - own.end).cwiseMax(0.0);
  const AlphaCounts posterior = dirichlet_posterior(prior, s, others);
  return {dirichlet_mean(posterior.subject), dirichlet_mean(posterior.confounders), dirichlet_mean(posterior.end)};
}

namespace {
// sum beta log(O / mean of beta): the prior's term, 0 at the prior's mean (so its size is
// that of the data's log-likelihood, whatever the prior's strength).
double weighted_log(const Eigen::MatrixXd& o, const Eigen::MatrixXd& beta) {
  const Eigen::MatrixXd mean = dirichlet_mean(beta);
  double sum = 0.0;
  for (Eigen::Index i = 0; i < beta.size(); ++i) {
    if (beta.data()[i] > 0.0) sum += beta.data()[i] * std::log(o.data()[i] / mean.data()[i]);
  }
  return sum;
}
}  // namespace

double log_prior_term(const ObservationModel& model, const ObservationPrior& prior, const ObservationPrior& alpha) {
  if (!alpha.learn || alpha.update != AlphaUpdate::kPosterior) return 0.0;
  return weighted_log(model.subject, weighed_subject_prior(prior, alpha.strength)) +
         weighted_log(model.confounders, prior.confounder_alpha) + weighted_log(model.end, weighed_end_prior(prior));
}

const std::vector<double>& prior_strength_grid() {
  static const std::vector<double> grid = [] {
    std::vector<double> g;
    for (int k = -6; k <= 6; ++k) g.push_back(std::pow(10.0, k / 2.0));
    return g;
  }();
  return grid;
}

void update_alpha(ObservationPrior& alpha, const ObservationPrior& prior, const AlphaCounts& alpha_dot) {
  const double c = alpha.c;
  if (alpha.update == AlphaUpdate::kPaper) {
    alpha.subject_alpha = c * alpha_dot.subject + (1.0 - c) * alpha.subject_alpha;
    alpha.confounder_alpha = c * alpha_dot.confounders + (1.0 - c) * alpha.confounder_alpha;
    if (alpha_dot.end.size() > 0) alpha.end_alpha = c * alpha_dot.end + (1.0 - c) * alpha.end_alpha;
    return;
  }
  // MAP-EM's M-step is exact (docs/MODEL.md): no step size, so nothing a user must choose
  // changes where EM goes.
  AlphaCounts target = dirichlet_posterior(prior, alpha.strength, alpha_dot);
  alpha.subject_alpha = std::move(target.subject);
  alpha.confounder_alpha = std::move(target.confounders);
  alpha.end_alpha = std::move(target.end);
}

}  // namespace hbirl
