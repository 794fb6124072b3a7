#include "learner/estep_mcmc.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace hbirl {

namespace {

double safe_log(double x) { return x > 0.0 ? std::log(x) : kNegInf; }

bool accept(double log_ratio, Rng& rng) {
  if (log_ratio >= 0.0) return true;
  if (log_ratio == kNegInf || std::isnan(log_ratio)) return false;
  return std::log(rng.uniform()) < log_ratio;
}

// One chain's state and the log-probability pieces the updates need.
class Chain {
 public:
  Chain(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model, const ObservedTrajectory& tr)
      : mdp_(mdp),
        policy_(policy),
        model_(model),
        tr_(tr),
        end_log_(end_log_evidence(mdp, tr, model.end)),
        T_(tr.length()),
        Z_(1 + model.num_confounders()) {
    s_.assign(static_cast<size_t>(T_), 0);
    a_.assign(static_cast<size_t>(T_), 0);
    copies_.resize(static_cast<size_t>(tr.num_observations()));
    labels_.assign(static_cast<size_t>(tr.num_observations()) * static_cast<size_t>(Z_), 0);
    for (int n = 0; n < tr.num_observations(); ++n) {
      const double w = tr.weight(n);
      if (w != std::floor(w) || w < 1.0) throw std::invalid_argument("McmcEngine: observation weights must be whole");
      copies_[static_cast<size_t>(n)] = static_cast<int>(w);
    }
  }

  int state(int t) const { return s_[static_cast<size_t>(t)]; }
  int action(int t) const { return a_[static_cast<size_t>(t)]; }
  int pair(int t) const { return mdp_.pair(state(t), action(t)); }
  int& label_count(int n, int z) {
    return labels_[static_cast<size_t>(n) * static_cast<size_t>(Z_) + static_cast<size_t>(z)];
  }

  // Start: every observation blamed on the element that explains it best (or the subject
  // if none can), then a trajectory drawn from the MDP until one has positive probability.
  bool initialise(Rng& rng) {
    for (int n = 0; n < tr_.num_observations(); ++n) {
      const int w = tr_.symbols[static_cast<size_t>(n)];
      int best = 0;
      double best_p = 0.0;
      for (int e = 0; e < model_.num_confounders(); ++e) {
        const double p = tr_.eta(n, e + 1) * model_.confounders(e, w);
        if (p > best_p) {
          best_p = p;
          best = e + 1;
        }
      }
      label_count(n, best) = copies_[static_cast<size_t>(n)];
    }
    for (int attempt = 0; attempt < 10000; ++attempt) {
      if (propose_from_prior(rng, s_, a_) && std::isfinite(log_joint())) return true;
    }
    return false;
  }

  // One sweep of paper Algorithm 1's inner loop: per step the labels, then s_t and a_t
  // (single_site), then optionally the whole path at once (block).
  void sweep(bool single_site, bool block, Rng& rng) {
    for (int t = 0; t < T_; ++t) {
      for (int n = tr_.step_begin[static_cast<size_t>(t)]; n < tr_.step_begin[static_cast<size_t>(t) + 1]; ++n)
        update_labels(n, t, rng);
      if (single_site) {
        update_state(t, rng);
        update_action(t, rng);
      }
    }
    if (block) update_block(rng);
  }

  // Pr(the last action entered s | the last pair r, the end's evidence), added to
  // row s of `out` once per end symbol: the end sensor's expected counts of this draw,
  // summed over s exactly (Rao-Blackwellised) rather than sampled.
  void add_end_counts(AlphaCounts& out) const {
    const int r = pair(T_ - 1);
    const double total = log_exit(r);
    if (total == kNegInf) return;
    for (SparseRowMatrix::InnerIterator it(mdp_.transitions, r); it; ++it) {
      const double log_q = safe_log(it.value()) + end_log_[it.col()] - total;
      if (log_q == kNegInf) continue;
      for (int w : tr_.end_symbols) out.end(it.col(), w) += std::exp(log_q);
    }
  }

 private:
  double log_transition(int r, int next) const { return safe_log(mdp_.transitions.coeff(r, next)); }

  // log of what the end says given the last pair r: log sum_s T(s | r) Pr(end | s)
  // (end_log_evidence), by log-sum-exp: reports far apart cannot underflow it.
  double log_exit(int r) const {
    if (tr_.end_symbols.empty()) {  // the evidence is 1 or 0: summed plainly (the bits of before)
      double p = 0.0;
      for (SparseRowMatrix::InnerIterator it(mdp_.transitions, r); it; ++it) {
        if (end_log_[it.col()] != kNegInf) p += it.value();
      }
      return safe_log(p);
    }
    double m = kNegInf;
    for (SparseRowMatrix::InnerIterator it(mdp_.transitions, r); it; ++it)
      m = std::max(m, safe_log(it.value()) + end_log_[it.col()]);
    if (m == kNegInf) return kNegInf;
    double sum = 0.0;
    for (SparseRowMatrix::InnerIterator it(mdp_.transitions, r); it; ++it) {
      const double x = safe_log(it.value()) + end_log_[it.col()];
      if (x != kNegInf) sum += std::exp(x - m);
    }
    return m + std::log(sum);
  }

  // sum over step t's observations labelled subject of log O_r(w).
  double log_subject_observations(int t, int r) {
    double sum = 0.0;
    for (int n = tr_.step_begin[static_cast<size_t>(t)]; n < tr_.step_begin[static_cast<size_t>(t) + 1]; ++n) {
      const int k = label_count(n, 0);
      if (k > 0) sum += k * safe_log(model_.subject(r, tr_.symbols[static_cast<size_t>(n)]));
    }
    return sum;
  }

  // The factors of the joint that involve the step-t pair (s, a), given its neighbours.
  double log_local(int t, int s, int a) {
    if (mdp_.is_terminal(s)) return kNegInf;
    const int r = mdp_.pair(s, a);
    double lp = policy_.log_policy[r];
    lp += t == 0 ? safe_log(mdp_.start[s]) : log_transition(pair(t - 1), s);
    if (t + 1 < T_) {
      lp += log_transition(r, state(t + 1));
    } else if (tr_.ends_in_terminal) {
      lp += log_exit(r);
    }
    return lp + log_subject_observations(t, r);
  }

  double log_joint() {
    double lp = 0.0;
    for (int t = 0; t < T_; ++t) {
      const int r = pair(t);
      lp += policy_.log_policy[r] + (t == 0 ? safe_log(mdp_.start[state(0)]) : log_transition(pair(t - 1), state(t)));
      if (mdp_.is_terminal(state(t))) return kNegInf;
      lp += log_subject_observations(t, r);
      for (int n = tr_.step_begin[static_cast<size_t>(t)]; n < tr_.step_begin[static_cast<size_t>(t) + 1]; ++n) {
        for (int z = 1; z < Z_; ++z) {
          if (label_count(n, z) > 0) {
            lp += label_count(n, z) * safe_log(model_.confounders(z - 1, tr_.symbols[static_cast<size_t>(n)]));
          }
        }
      }
    }
    if (tr_.ends_in_terminal) lp += log_exit(pair(T_ - 1));
    return lp;
  }

  double log_label(int n, int z, int r) const {
    const int w = tr_.symbols[static_cast<size_t>(n)];
    return safe_log(tr_.eta(n, z)) + safe_log(z == 0 ? model_.subject(r, w) : model_.confounders(z - 1, w));
  }

  // One MH update per copy of observation n. Copies are exchangeable, so only the counts
  // per label matter; each copy is updated exactly once per sweep, in the order of the
  // labels they held when the sweep reached them.
  void update_labels(int n, int t, Rng& rng) {
    const int r = pair(t);
    scratch_labels_.clear();
    for (int z = 0; z < Z_; ++z)
      scratch_labels_.insert(scratch_labels_.end(), static_cast<size_t>(label_count(n, z)), z);
    for (int z : scratch_labels_) {
      const int proposal = rng.uniform_int(Z_);
      if (proposal == z) continue;
      if (accept(log_label(n, proposal, r) - log_label(n, z, r), rng)) {
        --label_count(n, z);
        ++label_count(n, proposal);
      }
    }
  }

  void update_state(int t, Rng& rng) {
    const int proposal = rng.uniform_int(mdp_.num_states);
    const int current = state(t);
    if (proposal == current) return;
    const double old_lp = log_local(t, current, action(t));
    if (accept(log_local(t, proposal, action(t)) - old_lp, rng)) s_[static_cast<size_t>(t)] = proposal;
  }

  void update_action(int t, Rng& rng) {
    const int proposal = rng.uniform_int(mdp_.num_actions);
    const int current = action(t);
    if (proposal == current) return;
    // The predecessor term is the same for both actions; log_local includes it harmlessly.
    if (accept(log_local(t, state(t), proposal) - log_local(t, state(t), current), rng))
      a_[static_cast<size_t>(t)] = proposal;
  }

  // A trajectory from the MDP under the policy; false if it hit a terminal state early.
  bool propose_from_prior(Rng& rng, std::vector<int>& s, std::vector<int>& a) const {
    const int A = mdp_.num_actions;
    int state = rng.categorical(mdp_.start);
    for (int t = 0; t < T_; ++t) {
      if (mdp_.is_terminal(state)) return false;
      s[static_cast<size_t>(t)] = state;
      a[static_cast<size_t>(t)] = rng.categorical(policy_.policy.segment(static_cast<Eigen::Index>(state) * A, A));
      if (t + 1 < T_) {
        const int r = mdp_.pair(state, a[static_cast<size_t>(t)]);
        const int begin = mdp_.transitions.outerIndexPtr()[r];
        const int end = mdp_.transitions.outerIndexPtr()[r + 1];
        state = mdp_.transitions.innerIndexPtr()[begin + rng.categorical(Eigen::Map<const Eigen::VectorXd>(
                                                             mdp_.transitions.valuePtr() + begin, end - begin))];
      }
    }
    return true;
  }

  // Observation (and trajectory-end) likelihood of the current labels for a path.
  double log_path_likelihood(const std::vector<int>& s, const std::vector<int>& a) {
    double lp = 0.0;
    for (int t = 0; t < T_; ++t) {
      lp += log_subject_observations(t, mdp_.pair(s[static_cast<size_t>(t)], a[static_cast<size_t>(t)]));
    }
    if (tr_.ends_in_terminal) lp += log_exit(mdp_.pair(s.back(), a.back()));
    return lp;
  }

  // Independence MH with the MDP (under the policy) as the proposal: accept with the
  // ratio of the observation likelihoods.
  void update_block(Rng& rng) {
    std::vector<int> s(static_cast<size_t>(T_));
    std::vector<int> a(static_cast<size_t>(T_));
    if (!propose_from_prior(rng, s, a)) return;
    if (accept(log_path_likelihood(s, a) - log_path_likelihood(s_, a_), rng)) {
      s_.swap(s);
      a_.swap(a);
    }
  }

  const Mdp& mdp_;
  const SoftSolution& policy_;
  const ObservationModel& model_;
  const ObservedTrajectory& tr_;
  const Eigen::VectorXd end_log_;  // log Pr(end | s) (end_log_evidence)
  int T_;
  int Z_;
  std::vector<int> s_;
  std::vector<int> a_;
  std::vector<int> copies_;
  std::vector<int> labels_;  // N x Z copy counts
  std::vector<int> scratch_labels_;
};

bool deterministic(const Mdp& mdp) {
  for (int r = 0; r < mdp.num_pairs(); ++r) {
    if (mdp.transitions.outerIndexPtr()[r + 1] - mdp.transitions.outerIndexPtr()[r] > 1) return false;
  }
  return true;
}

// The convergence diagnostics of the pair marginals (docs/MODEL.md, "Is the MCMC E-step
// converged?"). paths[c] holds chain c's kept draws, each the pair of every step (T per
// draw); visits(t, r) counts the draws at pair r at step t over all chains. The draws of
// the marginal (t, r) are the indicators [pair at step t == r]. Only those visited in
// some draw but not in all are checked: a pair never (or always) at step t has identical
// draws, which carry no information about mixing (R-hat is 0/0), and checking only
// visited pairs keeps the cost to the pairs the posterior actually reaches.
McmcDiagnostics path_diagnostics(const std::vector<std::vector<int>>& paths, const RowMatrix& visits) {
  McmcDiagnostics out;
  out.chains = static_cast<int>(paths.size());
  const auto steps = static_cast<size_t>(visits.rows());
  if (steps == 0) return out;
  const size_t draws = paths.front().size() / steps;
  const double total = static_cast<double>(draws * paths.size());
  Chains indicators(paths.size(), std::vector<double>(draws));
  for (size_t t = 0; t < steps; ++t) {
    for (Eigen::Index r = 0; r < visits.cols(); ++r) {
      const double seen = visits(static_cast<Eigen::Index>(t), r);
      if (seen == 0.0 || seen == total) continue;
      for (size_t c = 0; c < paths.size(); ++c) {
        for (size_t d = 0; d < draws; ++d) indicators[c][d] = paths[c][d * steps + t] == r ? 1.0 : 0.0;
      }
      if (const std::optional<QuantityDiagnostics> q = diagnose(indicators)) out.add(*q);
    }
  }
  return out;
}

}  // namespace

McmcEngine::McmcEngine(const Mdp& mdp, McmcOptions options) : mdp_(mdp), options_(options), exact_(mdp) {
  const bool fixed_paths = deterministic(mdp);
  // Deterministic transitions: single-site moves of s or a cannot leave the current path.
  single_site_ = !fixed_paths && options.block != McmcOptions::Block::kOnly;
  block_ = options.block == McmcOptions::Block::kAlways || options.block == McmcOptions::Block::kOnly ||
           (options.block == McmcOptions::Block::kAuto && fixed_paths);
  if (options.samples < 1 || options.burn_in < 0 || options.chains < 1) {
    throw std::invalid_argument("McmcEngine: samples and chains must be positive, burn-in non-negative");
  }
}

bool McmcEngine::sample(const SoftSolution& policy, const ObservationModel& model, const ObservedTrajectory& trajectory,
                        Rng& rng, RowMatrix& marginals, RowMatrix& sources, AlphaCounts& alpha_dot,
                        McmcDiagnostics& diagnostics) {
  const int T = trajectory.length();
  const int Z = 1 + model.num_confounders();
  marginals = RowMatrix::Zero(T, mdp_.num_pairs());
  sources = RowMatrix::Zero(trajectory.num_observations(), Z);
  alpha_dot = AlphaCounts::zero(mdp_.num_pairs(), model.num_confounders(), model.num_symbols());
  if (!trajectory.end_symbols.empty()) alpha_dot.end = Eigen::MatrixXd::Zero(mdp_.num_states, model.end.cols());
  // Per chain, the pair of every step of every kept draw (for the diagnostics).
  std::vector<std::vector<int>> paths(static_cast<size_t>(options_.chains));
  for (int c = 0; c < options_.chains; ++c) {
    Rng chain_rng = rng.split(static_cast<std::uint64_t>(c));
    Chain chain(mdp_, policy, model, trajectory);
    if (!chain.initialise(chain_rng)) return false;
    std::vector<int>& path = paths[static_cast<size_t>(c)];
    path.reserve(static_cast<size_t>(options_.samples) * static_cast<size_t>(T));
    for (int sweep = 0; sweep < options_.burn_in + options_.samples; ++sweep) {
      chain.sweep(single_site_, block_, chain_rng);
      if (sweep < options_.burn_in) continue;
      if (!trajectory.end_symbols.empty()) chain.add_end_counts(alpha_dot);
      for (int t = 0; t < T; ++t) {
        const int r = chain.pair(t);
        marginals(t, r) += 1.0;
        path.push_back(r);
        for (int n = trajectory.step_begin[static_cast<size_t>(t)];
             n < trajectory.step_begin[static_cast<size_t>(t) + 1]; ++n) {
          const int w = trajectory.symbols[static_cast<size_t>(n)];
          for (int z = 0; z < Z; ++z) {
            const int k = chain.label_count(n, z);
            if (k == 0) continue;
            sources(n, z) += k / trajectory.weight(n);
            if (z == 0) {
              alpha_dot.subject(r, w) += k;
            } else {
              alpha_dot.confounders(z - 1, w) += k;
            }
          }
        }
      }
    }
  }
  diagnostics = path_diagnostics(paths, marginals);
  const double total = static_cast<double>(options_.samples) * options_.chains;
  marginals /= total;
  sources /= total;
  alpha_dot.subject /= total;
  alpha_dot.confounders /= total;
  alpha_dot.end /= total;
  return true;
}

TrajectoryPosterior McmcEngine::posterior(const SoftSolution& policy, const ObservationModel& model,
                                          const ObservedTrajectory& trajectory, Rng& rng) {
  TrajectoryPosterior out;
  out.log_likelihood = exact_.log_likelihood(policy, model, trajectory);
  AlphaCounts alpha_dot;
  if (out.log_likelihood == kNegInf ||
      !sample(policy, model, trajectory, rng, out.marginals, out.sources, alpha_dot, out.mcmc)) {
    out.log_likelihood = kNegInf;
    out.marginals =
        RowMatrix::Constant(trajectory.length(), mdp_.num_pairs(), std::numeric_limits<double>::quiet_NaN());
    out.sources = RowMatrix::Constant(trajectory.num_observations(), 1 + model.num_confounders(),
                                      std::numeric_limits<double>::quiet_NaN());
  }
  return out;
}

void McmcEngine::accumulate(const SoftSolution& policy, const ObservationModel& model,
                            const ObservedTrajectory& trajectory, Rng& rng, EStepStatistics& out) {
  const double ll = exact_.log_likelihood(policy, model, trajectory);
  RowMatrix marginals;
  RowMatrix sources;
  AlphaCounts alpha_dot;
  McmcDiagnostics diagnostics;
  // A block with end reports answers with end counts (zero when it is all impossible).
  if (!trajectory.end_symbols.empty() && out.alpha_dot.end.size() == 0)
    out.alpha_dot.end = Eigen::MatrixXd::Zero(mdp_.num_states, model.end.cols());
  if (ll == kNegInf || !sample(policy, model, trajectory, rng, marginals, sources, alpha_dot, diagnostics)) {
    ++out.impossible;
    return;
  }
  out.log_likelihood += ll;
  out.mcmc += diagnostics;
  out.counts += marginals.colwise().sum().transpose();
  out.alpha_dot += alpha_dot;
  if (out.source_counts.rows() > 0) {
    for (int n = 0; n < trajectory.num_observations(); ++n) {
      if (trajectory.context(n) >= 0)
        out.source_counts.row(trajectory.context(n)) += trajectory.weight(n) * sources.row(n);
    }
  }
}

EngineFactory mcmc_engine_factory(McmcOptions options) {
  return {[options](const Mdp& mdp) -> std::unique_ptr<PosteriorEngine> {
            return std::make_unique<McmcEngine>(mdp, options);
          },
          false};
}

}  // namespace hbirl
