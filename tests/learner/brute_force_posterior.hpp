#pragma once
// Independent truth for the E-step: the joint Pr(X, Z, observations) summed over every
// trajectory X of (s, a) pairs and every labelling Z of the observations. Exponential:
// tiny problems only.
#include <cmath>

#include "learner/estep_exact.hpp"

namespace hbirl::testing {

// Sums the joint Pr(X, Z, observations) over every trajectory X of pairs and every
// labelling Z of the observations.
struct BruteForce {
  double likelihood = 0.0;
  RowMatrix marginals;
  RowMatrix sources;
  Eigen::VectorXd end_states;  // Pr(the last action entered s | data) (trajectories that ended in one)
  EStepStatistics stats;
};

inline BruteForce brute_force(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                              const ObservedTrajectory& tr) {
  const int T = tr.length();
  const int P = mdp.num_pairs();
  const int N = tr.num_observations();
  const int Z = 1 + model.num_confounders();
  BruteForce out;
  out.marginals = RowMatrix::Zero(T, P);
  out.sources = RowMatrix::Zero(N, Z);
  out.stats = EStepStatistics::zero(P, model.num_confounders(), model.num_symbols());
  out.end_states = Eigen::VectorXd::Zero(mdp.num_states);
  if (!tr.end_symbols.empty()) out.stats.alpha_dot.end = Eigen::MatrixXd::Zero(mdp.num_states, model.end.cols());
  // Per terminal state: Pr(entered it, and the end it gave | the last pair).
  Eigen::VectorXd exits = Eigen::VectorXd::Zero(mdp.num_states);
  std::vector<int> step_of(static_cast<size_t>(N));
  for (int t = 0; t < T; ++t) {
    for (int n = tr.step_begin[static_cast<size_t>(t)]; n < tr.step_begin[static_cast<size_t>(t) + 1]; ++n) {
      step_of[static_cast<size_t>(n)] = t;
    }
  }
  int sequences = 1;
  for (int t = 0; t < T; ++t) sequences *= P;
  int labelings = 1;
  for (int n = 0; n < N; ++n) labelings *= Z;
  std::vector<int> pairs(static_cast<size_t>(T));
  std::vector<int> labels(static_cast<size_t>(N));
  for (int code = 0; code < sequences; ++code) {
    int c = code;
    for (int t = 0; t < T; ++t, c /= P) pairs[static_cast<size_t>(t)] = c % P;
    double prior = 1.0;
    for (int t = 0; t < T && prior > 0.0; ++t) {
      const int r = pairs[static_cast<size_t>(t)];
      const int s = r / mdp.num_actions;
      if (mdp.is_terminal(s)) prior = 0.0;
      prior *= (t == 0 ? mdp.start[s] : mdp.transitions.coeff(pairs[static_cast<size_t>(t) - 1], s)) * policy.policy[r];
    }
    double exit = 1.0;
    if (prior > 0.0 && tr.ends_in_terminal) {
      for (int s2 = 0; s2 < mdp.num_states; ++s2) {
        exits[s2] = 0.0;
        if (!mdp.is_terminal(s2) || (tr.end_state >= 0 && s2 != tr.end_state)) continue;
        exits[s2] = mdp.transitions.coeff(pairs[static_cast<size_t>(T) - 1], s2);
        for (int w : tr.end_symbols) exits[s2] *= model.end(s2, w);
      }
      exit = exits.sum();
      prior *= exit;
    }
    if (prior == 0.0) continue;
    double sequence = 0.0;  // Pr(this sequence, the data), over every labelling
    for (int lc = 0; lc < labelings; ++lc) {
      int l = lc;
      for (int n = 0; n < N; ++n, l /= Z) labels[static_cast<size_t>(n)] = l % Z;
      double joint = prior;
      for (int n = 0; n < N; ++n) {
        const int z = labels[static_cast<size_t>(n)];
        const int w = tr.symbols[static_cast<size_t>(n)];
        const int r = pairs[static_cast<size_t>(step_of[static_cast<size_t>(n)])];
        joint *= tr.eta(n, z) * (z == 0 ? model.subject(r, w) : model.confounders(z - 1, w));
      }
      out.likelihood += joint;
      sequence += joint;
      for (int t = 0; t < T; ++t) out.marginals(t, pairs[static_cast<size_t>(t)]) += joint;
      for (int n = 0; n < N; ++n) {
        const int z = labels[static_cast<size_t>(n)];
        const int w = tr.symbols[static_cast<size_t>(n)];
        out.sources(n, z) += joint;
        if (z == 0) {
          out.stats.alpha_dot.subject(pairs[static_cast<size_t>(step_of[static_cast<size_t>(n)])], w) += joint;
        } else {
          out.stats.alpha_dot.confounders(z - 1, w) += joint;
        }
      }
    }
    if (tr.ends_in_terminal) {
      out.end_states += sequence / exit * exits;
      for (int w : tr.end_symbols) out.stats.alpha_dot.end.col(w) += sequence / exit * exits;
    }
  }
  out.marginals /= out.likelihood;
  out.sources /= out.likelihood;
  out.stats.alpha_dot.subject /= out.likelihood;
  out.stats.alpha_dot.confounders /= out.likelihood;
  out.stats.alpha_dot.end /= out.likelihood;
  out.end_states /= out.likelihood;
  out.stats.counts = out.marginals.colwise().sum().transpose();
  out.stats.log_likelihood = std::log(out.likelihood);
  return out;
}

}  // namespace hbirl::testing
