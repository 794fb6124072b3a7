#pragma once
// Tiny random observed problems for the E-step engines: 3 states, 2 actions, 1-3 steps,
// at most 5 observations, 0-3 confounding elements, with occluded steps, terminal
// states, impossible actions and deterministic transitions in turn -- small enough for
// brute-force enumeration of every trajectory and labelling.
#include "learner/estep_exact.hpp"
#include "random_mdp.hpp"

namespace hbirl::testing {

struct TinyProblem {
  Mdp mdp;
  SoftSolution policy;
  ObservationModel model;
  ObservedTrajectory trajectory;
};

inline Eigen::MatrixXd random_distributions(int rows, int cols, Rng& rng) {
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) m(r, c) = 0.05 + rng.uniform();
    m.row(r) /= m.row(r).sum();
  }
  return m;
}

// dense: every (s, a) can reach every state (stochastic, no terminal states).
inline TinyProblem tiny_problem(int trial, Rng& rng, bool dense = false) {
  RandomMdpOptions o;
  o.states = 3;
  o.actions = 2;
  o.features = 2;
  o.successors = dense ? 3 : 2;
  o.deterministic = !dense && trial % 3 == 0;
  o.terminal = !dense && trial % 4 == 1 ? 1 : 0;
  o.impossible = trial % 5 == 2;
  TinyProblem p{random_mdp(o, rng), {}, {}, {}};
  p.policy = soft_value_iteration(p.mdp, p.mdp.reward(random_vector(2, rng, 2.0)));
  const int symbols = 2 + trial % 2;
  const int confounders = trial % 4;  // 0..3
  p.model.subject = random_distributions(p.mdp.num_pairs(), symbols, rng);
  p.model.confounders = random_distributions(confounders, symbols, rng);
  const int length = 1 + trial % 3;
  p.trajectory.ends_in_terminal = o.terminal > 0 && trial % 8 == 1;
  // At most 5 observations in all, so (1 + E)^N labelings stay enumerable.
  int budget = 5;
  std::vector<std::pair<int, Eigen::VectorXd>> observations;
  for (int t = 0; t < length; ++t) {
    const int n = t == 1 && trial % 2 == 0 ? 0 : std::min(budget, rng.uniform_int(3));  // some steps occluded
    budget -= n;
    for (int i = 0; i < n; ++i) {
      Eigen::VectorXd eta(1 + confounders);
      for (int z = 0; z <= confounders; ++z) eta[z] = rng.uniform() < 0.2 ? 0.0 : rng.uniform();
      if (eta.sum() == 0.0) eta[0] = 1.0;
      eta /= eta.sum();
      observations.emplace_back(rng.uniform_int(symbols), eta);
    }
    p.trajectory.step_begin.push_back(static_cast<int>(observations.size()));
  }
  p.trajectory.eta.resize(static_cast<Eigen::Index>(observations.size()), 1 + confounders);
  for (size_t i = 0; i < observations.size(); ++i) {
    p.trajectory.symbols.push_back(observations[i].first);
    p.trajectory.eta.row(static_cast<Eigen::Index>(i)) = observations[i].second.transpose();
  }
  return p;
}

// A prior whose Dirichlet mean is `model` (its rows are distributions), learned by default.
inline ObservationPrior prior_at(const ObservationModel& model) {
  ObservationPrior prior;
  prior.num_symbols = model.num_symbols();
  prior.num_confounders = model.num_confounders();
  prior.subject_alpha = model.subject;
  prior.confounder_alpha = model.confounders;
  return prior;
}

// A tiny problem whose MDP has two terminal states (states 2 and 3: a goal and a trap,
// say), every state reaching both or one of them, and whose trajectory ends by entering
// one (its end_state left unseen, -1).
inline TinyProblem two_exits(int trial, Rng& rng) {
  TinyProblem p = tiny_problem(trial, rng);  // its observations and elements
  RandomMdpOptions o;
  o.states = 4;
  o.actions = 2;
  o.features = 2;
  o.successors = 3;
  o.terminal = 2;
  p.mdp = random_mdp(o, rng);
  p.policy = soft_value_iteration(p.mdp, p.mdp.reward(random_vector(2, rng, 2.0)));
  p.model.subject = random_distributions(p.mdp.num_pairs(), static_cast<int>(p.model.subject.cols()), rng);
  p.trajectory.ends_in_terminal = true;
  return p;
}

}  // namespace hbirl::testing
