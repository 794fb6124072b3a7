#include "learner/estep_exact.hpp"

#include <cmath>
#include <limits>

namespace hbirl {

namespace {

// What the scaled passes return when they cannot be exact (the log-space passes decide).
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// v <- exp(v) elementwise, vectorised. Eigen's vectorised exp clamps its argument and maps
// -inf to the smallest normal double rather than 0: results below 1e-300 are set to
// exactly 0. Every caller has shifted v so that what matters is at least ~1e-16 (a
// maximum of 0, or a normalised probability), so nothing is lost.
template <typename Derived>
void exp_in_place(Eigen::DenseBase<Derived>& v) {
  v.derived().array() = v.derived().array().exp();
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (v.derived()[i] < 1e-300) v.derived()[i] = 0.0;
  }
}

// log sum_j exp(x_j) over a contiguous range; -inf for an empty or all -inf range.
double log_sum_exp(const double* x, Eigen::Index n) {
  double m = kNegInf;
  for (Eigen::Index j = 0; j < n; ++j) m = std::max(m, x[j]);
  if (m == kNegInf) return kNegInf;
  double sum = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) sum += std::exp(x[j] - m);
  return m + std::log(sum);
}

// log sum_j exp(w_j + v[index_j]) over one row of a sparse matrix of log weights.
double log_sum_exp_row(const SparseRowMatrix& log_w, int row, const double* v) {
  const int begin = log_w.outerIndexPtr()[row];
  const int end = log_w.outerIndexPtr()[row + 1];
  const int* index = log_w.innerIndexPtr();
  const double* w = log_w.valuePtr();
  double m = kNegInf;
  for (int j = begin; j < end; ++j) m = std::max(m, w[j] + v[index[j]]);
  if (m == kNegInf) return kNegInf;
  double sum = 0.0;
  for (int j = begin; j < end; ++j) sum += std::exp(w[j] + v[index[j]] - m);
  return m + std::log(sum);
}

// out = M x for a sparse row-major M, each row summed in four interleaved partial sums:
// the rows here are short (a state's predecessors, a pair's successors) and a single
// running sum would wait on every addition. The order is fixed: the same bits always.
void sparse_times(const SparseRowMatrix& m, const double* x, double* out) {
  const int* outer = m.outerIndexPtr();
  const int* inner = m.innerIndexPtr();
  const double* v = m.valuePtr();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    int j = outer[i];
    const int end = outer[i + 1];
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    for (; j + 4 <= end; j += 4) {
      s0 += v[j] * x[inner[j]];
      s1 += v[j + 1] * x[inner[j + 1]];
      s2 += v[j + 2] * x[inner[j + 2]];
      s3 += v[j + 3] * x[inner[j + 3]];
    }
    for (; j < end; ++j) s0 += v[j] * x[inner[j]];
    out[i] = (s0 + s1) + (s2 + s3);
  }
}

// Below this, a row of M exp(x - max) may have lost terms to underflow (exp_in_place
// drops what is under 1e-300): such rows are summed again in log space.
constexpr double kUnderflowFloor = 1e-250;

// The scaled passes (ExactEngine::scaled_passes): an entry of a forward message under
// kDropped may have lost precision or underflowed; the passes give way to the log-space
// ones when the mass that can have been lost reaches exp(kLogNegligible) of the kept, or
// a backward message exceeds kMaxScaledBackward. Emissions of pairs the forward message
// does not reach are capped at exp(kMaxScaledSpread) times the step's scale.
constexpr double kDropped = 1e-300;
constexpr double kLogNegligible = -69.0;  // ~1e-30
constexpr double kMaxScaledSpread = 600.0;
constexpr double kMaxScaledBackward = 1e250;
constexpr double kSmallNormaliser = 1e-20;

// out = log(M exp(x)) for a sparse non-negative M (log_m: its logs, same pattern),
// computed as exp(x - max) -> sparse product -> log + max: vectorised. A row whose sum
// falls below kUnderflowFloor (every term of it far below the maximum of x) is
// recomputed by its own log-sum-exp, so every row is exact to rounding: a dropped term
// is under 1e-300 of the maximum, i.e. under 1e-50 of any row that is kept.
void log_product(const SparseRowMatrix& m, const SparseRowMatrix& log_m, const Eigen::VectorXd& x, Eigen::VectorXd& out,
                 Eigen::VectorXd& scaled, std::vector<int>& low_rows) {
  double hi = kNegInf;
  for (Eigen::Index i = 0; i < x.size(); ++i) hi = std::max(hi, x[i]);
  if (hi == kNegInf) {
    out.setConstant(m.rows(), kNegInf);
    return;
  }
  scaled = x.array() - hi;
  exp_in_place(scaled);
  out.noalias() = m * scaled;
  low_rows.clear();
  for (Eigen::Index i = 0; i < out.size(); ++i) {
    if (out[i] < kUnderflowFloor) low_rows.push_back(static_cast<int>(i));
  }
  out = out.array().log() + hi;
  for (int i : low_rows) out[i] = log_sum_exp_row(log_m, i, x.data());
}

}  // namespace

EStepStatistics EStepStatistics::zero(int pairs, int confounders, int symbols, int contexts) {
  EStepStatistics s;
  s.counts = Eigen::VectorXd::Zero(pairs);
  s.alpha_dot = AlphaCounts::zero(pairs, confounders, symbols);
  s.source_counts = RowMatrix::Zero(contexts, 1 + confounders);
  return s;
}

EStepStatistics& EStepStatistics::operator+=(const EStepStatistics& other) {
  counts += other.counts;
  alpha_dot += other.alpha_dot;
  if (source_counts.size() == 0) {
    source_counts = other.source_counts;
  } else if (other.source_counts.size() > 0) {
    source_counts += other.source_counts;
  }
  log_likelihood += other.log_likelihood;
  impossible += other.impossible;
  mcmc += other.mcmc;
  if (other.watched.size() > 0) {
    watched = other.watched;
    watched_log_likelihood = other.watched_log_likelihood;
  }
  return *this;
}

ExactEngine::ExactEngine(const Mdp& mdp) : mdp_(mdp) {
  incoming_ = mdp.transitions.transpose();
  marginal_.resize(mdp.num_pairs());
  ratio_.resize(mdp.num_pairs());
  scratch_.resize(mdp.num_states);
  shift_.resize(mdp.num_pairs());
}

void ExactEngine::prepare_log_space() {
  if (log_start_.size() == mdp_.num_states) return;
  log_transitions_ = mdp_.transitions;
  for (Eigen::Index j = 0; j < log_transitions_.nonZeros(); ++j) {
    log_transitions_.valuePtr()[j] = std::log(log_transitions_.valuePtr()[j]);
  }
  log_incoming_ = log_transitions_.transpose();
  log_start_ = mdp_.start.array().log();
}

void ExactEngine::mixture(const ObservationModel& model, const ObservedTrajectory& trajectory, int n) {
  const int w = trajectory.symbols[static_cast<size_t>(n)];
  const double eta0 = trajectory.eta(n, 0);
  double confounded = 0.0;
  for (int e = 0; e < model.num_confounders(); ++e) confounded += trajectory.eta(n, e + 1) * model.confounders(e, w);
  p_.row(n) = (eta0 * model.subject.col(w).array() + confounded).transpose();
}

void ExactEngine::emissions(const ObservationModel& model, const ObservedTrajectory& trajectory) {
  log_emission_.setZero(trajectory.length(), mdp_.num_pairs());
  p_.resize(trajectory.num_observations(), mdp_.num_pairs());
  for (int t = 0; t < trajectory.length(); ++t) {
    for (int n = trajectory.step_begin[static_cast<size_t>(t)]; n < trajectory.step_begin[static_cast<size_t>(t) + 1];
         ++n) {
      mixture(model, trajectory, n);
      log_emission_.row(t).array() += trajectory.weight(n) * p_.row(n).array().log();
    }
  }
}

void ExactEngine::emissions(const ObservedTrajectory& trajectory, const std::vector<int>& kinds_of,
                            const KindEmissions& table) {
  log_emission_.setZero(trajectory.length(), mdp_.num_pairs());
  for (int t = 0; t < trajectory.length(); ++t) {
    for (int n = trajectory.step_begin[static_cast<size_t>(t)]; n < trajectory.step_begin[static_cast<size_t>(t) + 1];
         ++n) {
      log_emission_.row(t) += trajectory.weight(n) * table.log_p.row(kinds_of[static_cast<size_t>(n)]);
    }
  }
}

void ExactEngine::end_evidence(const ObservedTrajectory& trajectory, const Eigen::MatrixXd& end_model) {
  end_symbols_ = static_cast<int>(end_model.cols());
  if (trajectory.ends_in_terminal) end_log_ = end_log_evidence(mdp_, trajectory, end_model);
}

void ExactEngine::entered_state_posterior() {
  const int S = mdp_.num_states;
  entered_.resize(S);
  if (!scaled_) {
    // In log space, as the passes were: log q(s) = log e(s) + log sum_r gamma(r) T(s | r) /
    // beta_T(r), with log beta_T (log_beta_'s last row) the log of sum_s T(s | r) e(s) --
    // exact when the end's evidence spans more than a double's range.
    const Eigen::Index last = log_beta_.rows() - 1;
    previous_.resize(mdp_.num_pairs());
    for (int r = 0; r < mdp_.num_pairs(); ++r) {
      previous_[r] = marginal_[r] > 0.0 ? std::log(marginal_[r]) - log_beta_(last, r) : kNegInf;
    }
    for (int s = 0; s < S; ++s) {
      const double log_q =
          end_log_[s] == kNegInf ? kNegInf : end_log_[s] + log_sum_exp_row(log_incoming_, s, previous_.data());
      entered_[s] = log_q == kNegInf ? 0.0 : std::exp(log_q);
    }
    return;
  }
  // e shifted by its maximum: the ratios below do not change, nothing underflows that matters.
  scratch_.head(S) = shifted_exp(end_log_);
  const Eigen::VectorXd exit = mdp_.transitions * scratch_.head(S);  // per pair: sum_s T(s | r) e(s)
  ratio_ = (marginal_.array() > 0.0).select(marginal_.array() / exit.array(), 0.0);
  sparse_times(incoming_, ratio_.data(), entered_.data());
  entered_.array() *= scratch_.head(S).array();
}

void ExactEngine::add_end_counts(const ObservedTrajectory& trajectory, int end_symbols, AlphaCounts& out) {
  if (trajectory.end_symbols.empty()) return;
  if (out.end.size() == 0) out.end = Eigen::MatrixXd::Zero(mdp_.num_states, end_symbols);
  entered_state_posterior();
  for (int w : trajectory.end_symbols) out.end.col(w) += entered_;
}

double ExactEngine::forward_backward(const SoftSolution& policy, const ObservationModel& model,
                                     const ObservedTrajectory& trajectory, bool with_backward) {
  emissions(model, trajectory);
  end_evidence(trajectory, model.end);
  return passes(policy, trajectory, with_backward);
}

double ExactEngine::passes(const SoftSolution& policy, const ObservedTrajectory& trajectory, bool with_backward) {
  const double ll = scaled_passes(policy, trajectory, with_backward);
  scaled_ = !std::isnan(ll);
  return scaled_ ? ll : log_passes(policy, trajectory, with_backward);
}

double ExactEngine::scaled_passes(const SoftSolution& policy, const ObservedTrajectory& trajectory,
                                  bool with_backward) {
  const double forward = scaled_forward(policy, trajectory);
  if (!std::isfinite(forward)) return forward;  // impossible (-inf), or for the log-space passes (NaN)
  const double end = scaled_end(trajectory);
  if (std::isnan(end)) return end;
  const double ll = forward + end;
  if (!with_backward) return ll;
  return scaled_backward(policy, trajectory.length()) ? ll : kNaN;
}

double ExactEngine::scaled_forward(const SoftSolution& policy, const ObservedTrajectory& trajectory) {
  const int T = trajectory.length();
  const int S = mdp_.num_states;
  const int A = mdp_.num_actions;
  const int P = mdp_.num_pairs();
  const Eigen::VectorXd& pi = policy.policy;  // 0 on impossible pairs and terminal states
  // A pair is possible when log pi > -inf: pi itself may have underflowed to 0.
  const auto possible = policy.log_policy.array() > kNegInf;
  // Forward: a_t(r) = d_t(s) pi(r) e_t(r) exp(-m_t) with d_t = T^T alpha_hat_{t-1} (the start
  // distribution at t = 0), c_t = sum_r a_t(r), alpha_hat_t = a_t / c_t; then
  // log Pr(observations up to t) = sum_u (m_u + log c_u).
  //
  // What linear space can lose: entries of a_t under kDropped (products that underflow,
  // emissions exp_in_place flushes, priors d_t pi that round to 0), each truly below
  // kDropped times its emission over the scale, exp(log e - m_t) <= exp(reach_t - m_t)
  // (reach_t: the largest log emission over every pair the policy can take, which a lost
  // path may have reached). lost_[t] bounds, in units of alpha_hat_t, all the forward mass
  // lost up to t: what was lost before grows at most by exp(reach_t - m_t) / c_t per step,
  // and P kDropped exp(reach_t - m_t) / c_t joins it at a step that has a small entry.
  // Whatever looks impossible (nothing reached can emit, a zero sum) is left to the
  // log-space passes, which are exact about it.
  alpha_hat_.resize(T, P);
  emission_.resize(T, P);
  scale_.resize(T);
  lost_.resize(T);
  prior_.resize(P);
  row_.resize(P);
  double ll = 0.0;
  double log_lost = kNegInf;
  for (int t = 0; t < T; ++t) {
    if (t == 0) {
      scratch_ = mdp_.start;
    } else {
      sparse_times(incoming_, alpha_hat_.row(t - 1).data(), scratch_.data());
    }
    // Per pair: d_t(s) pi(a|s), which is 0 on terminal states (pi is).
    Eigen::Map<Eigen::MatrixXd>(prior_.data(), A, S) =
        Eigen::Map<const Eigen::MatrixXd>(pi.data(), A, S) * scratch_.asDiagonal();
    // m_t: the largest log emission among the pairs the forward message reaches.
    const auto log_e = log_emission_.row(t).transpose().array();
    double m = kNegInf;
    double reach = kNegInf;
    for (int r = 0; r < P; ++r) {
      const double x = log_e[r];
      const double if_reached = prior_[r] > 0.0 ? x : kNegInf;
      const double if_possible = possible[r] ? x : kNegInf;
      m = m < if_reached ? if_reached : m;
      reach = reach < if_possible ? if_possible : reach;
    }
    if (reach == kNegInf) return kNegInf;  // no pair can emit this step's observations
    // Nothing reached can emit this step's observations: impossible, unless the pairs that
    // can were reached by an underflowed product; the log-space passes tell which.
    if (m == kNegInf) return kNaN;
    // Emissions of pairs the message does not reach are capped: they only meet zeros
    // (unless mass was lost, which the bound below catches).
    auto emission = emission_.row(t);
    emission = (log_e - m).min(kMaxScaledSpread).transpose();
    exp_in_place(emission);
    auto a = alpha_hat_.row(t);
    a = prior_.transpose().cwiseProduct(emission);
    const double c = a.sum();
    const bool small = (possible && (a.transpose().array() < kDropped)).any();
    if (c == 0.0) return kNaN;
    if (!(c >= kUnderflowFloor)) return kNaN;
    const double carried = log_lost + (reach - m);
    // A small entry is truly under kDropped times its emission over the scale, at most
    // exp(reach - m) for a pair the message reached only by an underflowed product.
    const double dropped = small ? std::log(P * kDropped) + (reach - m) : kNegInf;
    log_lost = std::max(carried, dropped) + std::log1p(std::exp(-std::abs(carried - dropped))) - std::log(c);
    if (std::isnan(log_lost)) log_lost = kNegInf;  // both -inf
    if (!(log_lost <= kLogNegligible)) return kNaN;
    a /= c;
    scale_[t] = c;
    lost_[t] = log_lost;
    ll += m + std::log(c);
  }
  return ll;
}

double ExactEngine::scaled_end(const ObservedTrajectory& trajectory) {
  const int T = trajectory.length();
  const int S = mdp_.num_states;
  const int P = mdp_.num_pairs();
  // The last step's backward message: 1, or what the end says of the state the last
  // action entered, sum_s T(s | r) Pr(end | s) (end_log_, shifted by its maximum `top`,
  // which is added back to the log-likelihood), when the trajectory is known to have
  // ended by entering a terminal state.
  beta_hat_.resize(T, P);
  double top = 0.0;
  if (trajectory.ends_in_terminal) {
    scratch_.head(S) = shifted_exp(end_log_, &top);
    if (top == kNegInf) return kNegInf;  // no terminal state can give this end
    beta_hat_.row(T - 1).noalias() = (mdp_.transitions * scratch_).transpose();
  } else {
    beta_hat_.row(T - 1).setOnes();
  }
  normaliser_ = alpha_hat_.row(T - 1).dot(beta_hat_.row(T - 1));
  if (normaliser_ == 0.0) return kNaN;  // impossible, or underflowed: the log-space passes tell
  // The lost mass against the kept at the last step (beta_hat <= 1 there).
  if (!(normaliser_ >= kUnderflowFloor) || !(lost_[T - 1] - std::log(normaliser_) <= kLogNegligible)) return kNaN;
  return std::log(normaliser_) + top;
}

bool ExactEngine::scaled_backward(const SoftSolution& policy, int T) {
  const int S = mdp_.num_states;
  const int A = mdp_.num_actions;
  const Eigen::VectorXd& pi = policy.policy;
  // A small normaliser (an unlikely end in a terminal state) would take the backward
  // products below the smallest double: a product whose share of a marginal is over
  // 1e-30 is at least 1e-30 c_{t+1} Z >= 1e-280 Z. Below kSmallNormaliser the last
  // backward message is divided by it, so that sum_r alpha_hat_t beta_hat_t = 1.
  backward_total_ = normaliser_;
  if (normaliser_ < kSmallNormaliser) {
    beta_hat_.row(T - 1) /= normaliser_;
    backward_total_ = 1.0;
  }
  // Backward: beta_hat_t(r) = sum_s' T(s'|r) g(s') / c_{t+1},
  //           g(s') = sum_a' pi(a'|s') e_{t+1}(s',a') beta_hat_{t+1}(s',a'),
  // so that alpha_hat_t beta_hat_t / backward_total_ is the marginal at every step.
  for (int t = T - 2; t >= 0; --t) {
    prior_ = pi.cwiseProduct(emission_.row(t + 1).transpose()).cwiseProduct(beta_hat_.row(t + 1).transpose());
    scratch_ = Eigen::Map<const Eigen::MatrixXd>(prior_.data(), A, S).colwise().sum().transpose();
    sparse_times(mdp_.transitions, scratch_.data(), row_.data());
    row_ /= scale_[t + 1];
    // Lost forward mass meets these messages at step t: it must stay negligible against
    // the marginals' total (backward_total_), and the messages within the double range.
    const double largest = row_.maxCoeff();
    if (!(largest <= kMaxScaledBackward) ||
        !(lost_[t] + std::log(std::max(largest, 1.0)) - std::log(backward_total_) <= kLogNegligible)) {
      return false;
    }
    beta_hat_.row(t) = row_.transpose();
  }
  return true;
}

double ExactEngine::log_passes(const SoftSolution& policy, const ObservedTrajectory& trajectory, bool with_backward) {
  prepare_log_space();
  const int T = trajectory.length();
  const int S = mdp_.num_states;
  const int A = mdp_.num_actions;
  const int P = mdp_.num_pairs();
  // Forward: log alpha_t(s,a) = log d_t(s) + log pi(a|s) + log e_t(s,a), where
  // log d_t(s) = logsumexp over the pairs r leading into s of log alpha_{t-1}(r) + log T(s|r).
  log_alpha_.resize(T, P);
  for (int t = 0; t < T; ++t) {
    if (t == 0) {
      scratch_ = log_start_;
    } else {
      previous_ = log_alpha_.row(t - 1).transpose();
      log_product(incoming_, log_incoming_, previous_, scratch_, shifted_, low_rows_);
    }
    for (int s = 0; s < S; ++s) {
      if (mdp_.is_terminal(s)) scratch_[s] = kNegInf;  // never occupied at a step
      for (int a = 0; a < A; ++a) {
        const int r = s * A + a;
        const double lp = policy.log_policy[r];
        log_alpha_(t, r) = (scratch_[s] == kNegInf || lp == kNegInf) ? kNegInf : scratch_[s] + lp + log_emission_(t, r);
      }
    }
  }
  // Backward: log beta_t(r) = logsumexp_s' [log T(s'|r) + log g_{t+1}(s')],
  //           log g(s') = logsumexp_a' [log pi(a'|s') + log e(s',a') + log beta(s',a')].
  // At the last step beta is 1, or log sum_s T(s | r) Pr(end | s) when the trajectory
  // is known to have ended by entering a terminal state (end_log_).
  log_beta_.resize(T, P);
  if (trajectory.ends_in_terminal) {
    scratch_.head(S) = end_log_;
    for (int r = 0; r < P; ++r) log_beta_(T - 1, r) = log_sum_exp_row(log_transitions_, r, scratch_.data());
  } else {
    log_beta_.row(T - 1).setZero();
  }
  Eigen::VectorXd last = log_alpha_.row(T - 1).transpose() + log_beta_.row(T - 1).transpose();
  const double ll = log_sum_exp(last.data(), P);
  if (ll == kNegInf || std::isnan(ll)) return kNegInf;
  if (!with_backward) return ll;
  Eigen::VectorXd terms(P);
  for (int t = T - 2; t >= 0; --t) {
    for (int r = 0; r < P; ++r) {
      const double lp = policy.log_policy[r];
      terms[r] = lp == kNegInf ? kNegInf : lp + log_emission_(t + 1, r) + log_beta_(t + 1, r);
    }
    // log g(s') = logsumexp over the A actions of s': the maxima per state first, then
    // one vectorised exp over all pairs (exp(-inf) = 0 for impossible pairs).
    for (int s = 0; s < S; ++s) {
      const double* x = terms.data() + static_cast<Eigen::Index>(s) * A;
      double m = kNegInf;
      if (!mdp_.is_terminal(s)) {
        for (int a = 0; a < A; ++a) m = std::max(m, x[a]);
      }
      scratch_[s] = m;
      for (int a = 0; a < A; ++a) shift_[s * A + a] = m == kNegInf ? kNegInf : x[a] - m;
    }
    exp_in_place(shift_);
    for (int s = 0; s < S; ++s) {
      if (scratch_[s] == kNegInf) continue;
      double sum = 0.0;
      for (int a = 0; a < A; ++a) sum += shift_[s * A + a];
      scratch_[s] += std::log(sum);
    }
    log_product(mdp_.transitions, log_transitions_, scratch_, row_, shifted_, low_rows_);
    log_beta_.row(t) = row_.transpose();
  }
  return ll;
}

void ExactEngine::marginal(int t, double log_likelihood) {
  if (scaled_) {
    marginal_ = (alpha_hat_.row(t).array() * beta_hat_.row(t).array()).transpose() / backward_total_;
    return;
  }
  // -inf (alpha or beta) gives exactly 0; beta is never +inf.
  marginal_ = (log_alpha_.row(t).array() + log_beta_.row(t).array() - log_likelihood).transpose();
  exp_in_place(marginal_);
}

TrajectoryPosterior ExactEngine::posterior(const SoftSolution& policy, const ObservationModel& model,
                                           const ObservedTrajectory& trajectory) {
  TrajectoryPosterior out;
  const int T = trajectory.length();
  out.log_likelihood = forward_backward(policy, model, trajectory);
  out.marginals = RowMatrix::Zero(T, mdp_.num_pairs());
  out.sources = RowMatrix::Zero(trajectory.num_observations(), 1 + model.num_confounders());
  if (out.log_likelihood == kNegInf) {
    out.sources.setConstant(std::numeric_limits<double>::quiet_NaN());
    out.marginals.setConstant(std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  for (int t = 0; t < T; ++t) {
    marginal(t, out.log_likelihood);
    out.marginals.row(t) = marginal_.transpose();
    for (int n = trajectory.step_begin[static_cast<size_t>(t)]; n < trajectory.step_begin[static_cast<size_t>(t) + 1];
         ++n) {
      const int w = trajectory.symbols[static_cast<size_t>(n)];
      // gamma / p, with 0 where gamma = 0 (p may be 0 there).
      ratio_ = (marginal_.array() > 0.0).select(marginal_.array() / p_.row(n).transpose().array(), 0.0);
      out.sources(n, 0) = trajectory.eta(n, 0) * (ratio_ * model.subject.col(w).array()).sum();
      const double total = ratio_.sum();
      for (int e = 0; e < model.num_confounders(); ++e) {
        out.sources(n, e + 1) = trajectory.eta(n, e + 1) * model.confounders(e, w) * total;
      }
    }
  }
  if (trajectory.ends_in_terminal) {  // marginal_ holds the last step's
    entered_state_posterior();
    out.end_states = entered_;
  }
  return out;
}

template <typename PerObservation>
void ExactEngine::add_marginals(const ObservedTrajectory& trajectory, double ll, EStepStatistics& out, bool watch,
                                PerObservation&& per_observation) {
  if (watch) out.watched_log_likelihood = ll;
  // A block with end reports answers with end counts (zero when it is all impossible).
  if (!trajectory.end_symbols.empty() && out.alpha_dot.end.size() == 0)
    out.alpha_dot.end = Eigen::MatrixXd::Zero(mdp_.num_states, end_symbols_);
  if (ll == kNegInf) {
    ++out.impossible;
    return;
  }
  out.log_likelihood += ll;
  if (watch) out.watched.resize(trajectory.length(), marginal_.size());
  for (int t = 0; t < trajectory.length(); ++t) {
    marginal(t, ll);
    out.counts += marginal_;
    if (watch) out.watched.row(t) = marginal_.transpose();
    for (int n = trajectory.step_begin[static_cast<size_t>(t)]; n < trajectory.step_begin[static_cast<size_t>(t) + 1];
         ++n) {
      per_observation(n);
    }
  }
  add_end_counts(trajectory, end_symbols_, out.alpha_dot);  // marginal_ holds the last step's
}

void ExactEngine::accumulate(const SoftSolution& policy, const ObservationModel& model,
                             const ObservedTrajectory& trajectory, EStepStatistics& out, bool watch) {
  const double ll = forward_backward(policy, model, trajectory);
  add_marginals(trajectory, ll, out, watch, [&](int n) {
    const int w = trajectory.symbols[static_cast<size_t>(n)];
    ratio_ = (marginal_.array() > 0.0).select(marginal_.array() / p_.row(n).transpose().array(), 0.0);
    const double weight = trajectory.weight(n);
    out.alpha_dot.subject.col(w).array() += (weight * trajectory.eta(n, 0)) * ratio_ * model.subject.col(w).array();
    const double total = weight * ratio_.sum();
    const int context = trajectory.context(n);
    const bool by_context = context >= 0 && out.source_counts.rows() > 0;
    if (by_context)
      out.source_counts(context, 0) += weight * trajectory.eta(n, 0) * (ratio_ * model.subject.col(w).array()).sum();
    for (int e = 0; e < model.num_confounders(); ++e) {
      const double share = trajectory.eta(n, e + 1) * model.confounders(e, w) * total;
      out.alpha_dot.confounders(e, w) += share;
      if (by_context) out.source_counts(context, e + 1) += share;
    }
  });
}

void ExactEngine::accumulate(const SoftSolution& policy, const ObservedTrajectory& trajectory,
                             const std::vector<int>& kinds_of, const KindEmissions& emissions_table,
                             EStepStatistics& out, RowMatrix& kind_gamma, std::vector<char>& seen,
                             std::vector<int>& touched, bool watch) {
  emissions(trajectory, kinds_of, emissions_table);
  end_evidence(trajectory, emissions_table.end);
  const double ll = passes(policy, trajectory, true);
  add_marginals(trajectory, ll, out, watch, [&](int n) {
    const int k = kinds_of[static_cast<size_t>(n)];
    if (!seen[static_cast<size_t>(k)]) {
      seen[static_cast<size_t>(k)] = 1;
      touched.push_back(k);
    }
    kind_gamma.row(k) += trajectory.weight(n) * marginal_.transpose();
  });
}

KindEmissions kind_emissions(const ObservationModel& model, const ObservationKinds& kinds) {
  KindEmissions out;
  const Eigen::Index pairs = model.subject.rows();
  out.p.resize(kinds.num_kinds(), pairs);
  for (int k = 0; k < kinds.num_kinds(); ++k) {
    const int w = kinds.symbols[static_cast<size_t>(k)];
    double confounded = 0.0;
    for (int e = 0; e < model.num_confounders(); ++e) confounded += kinds.eta(k, e + 1) * model.confounders(e, w);
    out.p.row(k) = (kinds.eta(k, 0) * model.subject.col(w).array() + confounded).transpose();
  }
  out.log_p = out.p.array().log();
  out.end = model.end;
  return out;
}

void add_kind_alpha_dot(const ObservationModel& model, const ObservationKinds& kinds, const KindEmissions& emissions,
                        const RowMatrix& kind_gamma, const std::vector<int>& touched, AlphaCounts& out,
                        RowMatrix& source_counts) {
  for (int k : touched) {
    const int w = kinds.symbols[static_cast<size_t>(k)];
    // G / p, with 0 where G = 0 (p may be 0 there).
    const Eigen::ArrayXd ratio = (kind_gamma.row(k).array() > 0.0)
                                     .select(kind_gamma.row(k).array() / emissions.p.row(k).array(), 0.0)
                                     .transpose();
    const Eigen::ArrayXd subject = kinds.eta(k, 0) * ratio * model.subject.col(w).array();
    out.subject.col(w).array() += subject;
    const double total = ratio.sum();
    const int context = kinds.contexts.empty() ? -1 : kinds.contexts[static_cast<size_t>(k)];
    const bool by_context = context >= 0 && source_counts.rows() > 0;
    if (by_context) source_counts(context, 0) += subject.sum();
    for (int e = 0; e < model.num_confounders(); ++e) {
      const double share = kinds.eta(k, e + 1) * model.confounders(e, w) * total;
      out.confounders(e, w) += share;
      if (by_context) source_counts(context, e + 1) += share;
    }
  }
}

void accumulate_by_kind(ExactEngine& exact, const SoftSolution& policy, const ObservationModel& model,
                        const std::vector<ObservedTrajectory>& trajectories, int begin, int end,
                        const ObservationKinds& kinds, const KindEmissions& table, int watch, EStepStatistics& out) {
  RowMatrix kind_gamma = RowMatrix::Zero(kinds.num_kinds(), table.p.cols());
  std::vector<char> seen(static_cast<size_t>(kinds.num_kinds()), 0);
  std::vector<int> touched;
  for (int k = begin; k < end; ++k) {
    exact.accumulate(policy, trajectories[static_cast<size_t>(k)], kinds.of[static_cast<size_t>(k)], table, out,
                     kind_gamma, seen, touched, k == watch);
  }
  add_kind_alpha_dot(model, kinds, table, kind_gamma, touched, out.alpha_dot, out.source_counts);
}

}  // namespace hbirl
