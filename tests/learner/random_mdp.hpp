#pragma once
// Random small MDPs for property tests: stochastic transitions with a few successors per
// (s, a), optional terminal states and impossible actions, random real features.
#include <algorithm>

#include "learner/mdp.hpp"
#include "learner/rng.hpp"

namespace hbirl::testing {

struct RandomMdpOptions {
  int states = 6;
  int actions = 3;
  int features = 4;
  int successors = 3;
  int terminal = 0;            // the last `terminal` states are terminal
  bool impossible = false;     // make some actions impossible (never all of a state's)
  bool deterministic = false;  // one successor per (s, a)
  double discount = 0.9;
};

inline Mdp random_mdp(const RandomMdpOptions& o, Rng& rng) {
  std::vector<TransitionEntry> transitions;
  const int live = o.states - o.terminal;
  for (int s = 0; s < live; ++s) {
    for (int a = 0; a < o.actions; ++a) {
      if (o.impossible && a > 0 && rng.uniform() < 0.3) continue;
      const int k = o.deterministic ? 1 : o.successors;
      std::vector<double> w(static_cast<size_t>(k));
      double sum = 0.0;
      for (auto& x : w) sum += (x = 0.1 + rng.uniform());
      std::vector<int> used;
      for (int j = 0; j < k; ++j) {
        int s2 = rng.uniform_int(o.states);
        while (std::find(used.begin(), used.end(), s2) != used.end()) s2 = rng.uniform_int(o.states);
        used.push_back(s2);
        transitions.push_back({s, a, s2, w[static_cast<size_t>(j)] / sum});
      }
    }
  }
  std::vector<FeatureEntry> features;
  for (int s = 0; s < o.states; ++s) {
    for (int a = 0; a < o.actions; ++a) {
      for (int f = 0; f < o.features; ++f) features.push_back({s, a, f, rng.uniform(-1.0, 1.0)});
    }
  }
  Eigen::VectorXd start = Eigen::VectorXd::Zero(o.states);
  for (int s = 0; s < live; ++s) start[s] = 0.2 + rng.uniform();
  start /= start.sum();
  std::vector<int> terminal;
  for (int s = live; s < o.states; ++s) terminal.push_back(s);
  Mdp mdp = make_mdp(o.states, o.actions, o.features, transitions, features, start, terminal, o.discount);
  mdp.validate();
  return mdp;
}

// The trial-th member of a family that cycles through sizes (2-10 states, 1-4 actions,
// 1-5 features), terminal states, impossible actions, deterministic transitions and
// discounts 0, 0.9 and 0.99.
inline RandomMdpOptions varied_options(int trial) {
  RandomMdpOptions o;
  o.states = 2 + trial % 9;
  o.actions = 1 + trial % 4;
  o.features = 1 + trial % 5;
  o.successors = std::min(3, o.states);
  o.terminal = (trial % 3 == 0 && o.states > 2) ? 1 : 0;
  o.impossible = trial % 2 == 0;
  o.deterministic = trial % 4 == 1;
  o.discount = trial % 5 == 0 ? 0.99 : (trial % 5 == 1 ? 0.0 : 0.9);
  return o;
}

inline Eigen::VectorXd random_vector(int n, Rng& rng, double scale = 1.0) {
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = rng.uniform(-scale, scale);
  return v;
}

}  // namespace hbirl::testing
