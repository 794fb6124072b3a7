#include "learner/trajectory.hpp"

#include <algorithm>

namespace hbirl {

Trajectory sample_trajectory(const Mdp& mdp, const Eigen::VectorXd& policy, int length, Rng& rng,
                             bool* entered_terminal, int* entered_state) {
  if (entered_terminal) *entered_terminal = false;
  if (entered_state) *entered_state = -1;
  Trajectory trajectory;
  trajectory.reserve(static_cast<size_t>(std::max(length, 0)));
  const int A = mdp.num_actions;
  int s = rng.categorical(mdp.start);
  for (int t = 0; t < length; ++t) {
    const int a = rng.categorical(policy.segment(static_cast<Eigen::Index>(s) * A, A));
    trajectory.push_back({s, a});
    const int r = mdp.pair(s, a);
    const int begin = mdp.transitions.outerIndexPtr()[r];
    const int end = mdp.transitions.outerIndexPtr()[r + 1];
    const int j =
        begin + rng.categorical(Eigen::Map<const Eigen::VectorXd>(mdp.transitions.valuePtr() + begin, end - begin));
    s = mdp.transitions.innerIndexPtr()[j];
    if (mdp.is_terminal(s)) {
      if (entered_terminal) *entered_terminal = true;
      if (entered_state) *entered_state = s;
      break;
    }
  }
  return trajectory;
}

double probability_of_ending_within(const Mdp& mdp, const Eigen::VectorXd& policy, int length) {
  Eigen::VectorXd occupied = mdp.start;  // over states not yet ended
  double ended = 0.0;
  for (int t = 0; t < length; ++t) {
    Eigen::VectorXd next = Eigen::VectorXd::Zero(mdp.num_states);
    for (int s = 0; s < mdp.num_states; ++s) {
      if (occupied[s] == 0.0 || mdp.is_terminal(s)) continue;
      for (int a = 0; a < mdp.num_actions; ++a) {
        const double p = occupied[s] * policy[mdp.pair(s, a)];
        if (p == 0.0) continue;
        for (SparseRowMatrix::InnerIterator it(mdp.transitions, mdp.pair(s, a)); it; ++it) {
          const auto to = static_cast<int>(it.col());
          if (mdp.is_terminal(to)) {
            ended += p * it.value();
          } else {
            next[to] += p * it.value();
          }
        }
      }
    }
    occupied = std::move(next);
    if (occupied.sum() < 1e-15) break;  // every trajectory has ended
  }
  return std::min(ended, 1.0);  // (rounding)
}

Eigen::VectorXd visit_counts(const Mdp& mdp, const std::vector<Trajectory>& trajectories) {
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(mdp.num_pairs());
  for (const auto& trajectory : trajectories) {
    for (const auto& step : trajectory) counts[mdp.pair(step.state, step.action)] += 1.0;
  }
  return counts;
}

}  // namespace hbirl
