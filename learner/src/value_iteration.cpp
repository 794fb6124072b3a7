#include "learner/value_iteration.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "learner/policy_matrix.hpp"

namespace hbirl {

namespace {
constexpr int kMaxPolicyIterations = 1000;

// q = R + gamma T v with -inf on impossible pairs and terminal states.
void q_values(const Mdp& mdp, const Eigen::VectorXd& reward, const Eigen::VectorXd& v, Eigen::VectorXd& q) {
  q.noalias() = mdp.transitions * v;
  q = reward + mdp.discount * q;
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      if (mdp.is_terminal(s) || !mdp.available(s, a)) q[mdp.pair(s, a)] = kNegInf;
    }
  }
}

// One Gauss-Seidel sweep of value iteration with each action's self-loop solved exactly:
//   v(s) <- max_a (R(s,a) + gamma sum_{s' != s} T(s'|s,a) v(s')) / (1 - gamma T(s|s,a)),
// states in turn, each using the values already updated in this sweep; the direction
// alternates between sweeps. V* is its fixed point (for the maximising action the
// Bellman equation solved for v(s) is this; for any other, Bellman's inequality divided
// by 1 - gamma T(s|s,a) > 0), and it contracts at least by gamma. Plain sweeps contract by
// gamma exactly where a state mostly stays put (a wall, a goal held): 392 sweeps for
// 1e-10 on the 200 x 200 gridworld at gamma = 0.95, against 71 for these
// (docs/BENCHMARKS.md, BM_ValueIteration). Returns the largest change.
double self_loop_gauss_seidel_sweep(const Mdp& mdp, const Eigen::VectorXd& reward, bool forward, Eigen::VectorXd& v) {
  const int S = mdp.num_states;
  const int A = mdp.num_actions;
  const int* outer = mdp.transitions.outerIndexPtr();
  const int* inner = mdp.transitions.innerIndexPtr();
  const double* p = mdp.transitions.valuePtr();
  double change = 0.0;
  for (int i = 0; i < S; ++i) {
    const int s = forward ? i : S - 1 - i;
    if (mdp.is_terminal(s)) continue;
    double best = kNegInf;
    for (int a = 0; a < A; ++a) {
      if (!mdp.available(s, a)) continue;
      const int r = s * A + a;
      double elsewhere = 0.0;
      double stay = 0.0;
      for (int j = outer[r]; j < outer[r + 1]; ++j) {
        if (inner[j] == s) {
          stay += p[j];
        } else {
          elsewhere += p[j] * v[inner[j]];
        }
      }
      best = std::max(best, (reward[r] + mdp.discount * elsewhere) / (1.0 - mdp.discount * stay));
    }
    change = std::max(change, std::abs(best - v[s]));
    v[s] = best;
  }
  return change;
}

Eigen::VectorXd solve_policy(PolicyMatrix& matrix, const Eigen::VectorXd& b, const Eigen::VectorXd* guess) {
  Eigen::VectorXd x = guess && guess->size() == b.size() ? *guess : b;
  if (!matrix.solve(b, x)) {
    // Neumann series: x = b + gamma P_pi x, a contraction for gamma < 1.
    const SparseRowMatrix& m = matrix.matrix();
    for (int it = 0; it < 1000000; ++it) {
      Eigen::VectorXd next = b + x - m * x;
      const double change = (next - x).lpNorm<Eigen::Infinity>();
      x.swap(next);
      if (change <= 1e-14 * std::max(1.0, x.lpNorm<Eigen::Infinity>())) break;
    }
  }
  return x;
}
}  // namespace

OptimalPolicy value_iteration(const Mdp& mdp, const Eigen::VectorXd& reward, double tolerance) {
  const int S = mdp.num_states;
  const int A = mdp.num_actions;
  OptimalPolicy result;
  // A NaN would slip through the sweeps' max unnoticed (impossible pairs are never read).
  for (int s = 0; s < S; ++s) {
    for (int a = 0; a < A; ++a) {
      if (!mdp.is_terminal(s) && mdp.available(s, a) && !std::isfinite(reward[mdp.pair(s, a)])) {
        throw std::domain_error("value_iteration: reward is not finite");
      }
    }
  }
  Eigen::VectorXd v = Eigen::VectorXd::Zero(S);
  Eigen::VectorXd& q = result.q;
  for (;;) {
    const double change = self_loop_gauss_seidel_sweep(mdp, reward, result.iterations % 2 == 0, v);
    ++result.iterations;
    if (!std::isfinite(change)) throw std::domain_error("value_iteration: a state has no finite value");
    if (change <= tolerance * std::max(1.0, v.lpNorm<Eigen::Infinity>())) break;
  }
  q_values(mdp, reward, v, q);
  result.actions.assign(static_cast<size_t>(S), -1);
  for (int s = 0; s < S; ++s) {
    if (mdp.is_terminal(s)) continue;
    Eigen::Index best = 0;
    q.segment(static_cast<Eigen::Index>(s) * A, A).maxCoeff(&best);
    result.actions[static_cast<size_t>(s)] = static_cast<int>(best);
  }
  // Policy iteration polish: switch an action only for a gain beyond rounding noise. Each
  // evaluation starts from the last values (value iteration's, then the previous policy's).
  result.value = v;
  for (;;) {
    const Eigen::VectorXd previous = std::move(result.value);
    result.value = policy_evaluation(mdp, reward, result.actions, &previous);
    q_values(mdp, reward, result.value, q);
    const double noise = 1e-12 * std::max(1.0, result.value.lpNorm<Eigen::Infinity>());
    bool improved = false;
    for (int s = 0; s < S; ++s) {
      if (mdp.is_terminal(s)) continue;
      Eigen::Index best = 0;
      const double best_q = q.segment(static_cast<Eigen::Index>(s) * A, A).maxCoeff(&best);
      if (best_q > q[mdp.pair(s, result.actions[static_cast<size_t>(s)])] + noise) {
        result.actions[static_cast<size_t>(s)] = static_cast<int>(best);
        improved = true;
      }
    }
    if (!improved || ++result.policy_iterations >= kMaxPolicyIterations) break;
  }
  return result;
}

Eigen::VectorXd policy_evaluation(const Mdp& mdp, const Eigen::VectorXd& reward, const std::vector<int>& actions,
                                  const Eigen::VectorXd* guess) {
  if (actions.size() != static_cast<size_t>(mdp.num_states)) {
    throw std::invalid_argument("policy_evaluation: one action per state expected");
  }
  Eigen::VectorXd policy = Eigen::VectorXd::Zero(mdp.num_pairs());
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) continue;
    const int a = actions[static_cast<size_t>(s)];
    if (a < 0 || a >= mdp.num_actions || !mdp.available(s, a)) {
      throw std::invalid_argument("policy_evaluation: impossible action in state " + std::to_string(s));
    }
    policy[mdp.pair(s, a)] = 1.0;
  }
  return policy_evaluation(mdp, reward, policy, guess);
}

Eigen::VectorXd policy_evaluation(const Mdp& mdp, const Eigen::VectorXd& reward, const Eigen::VectorXd& policy,
                                  const Eigen::VectorXd* guess) {
  const int A = mdp.num_actions;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(mdp.num_states);
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) continue;
    for (int a = 0; a < A; ++a) {
      const int r = s * A + a;
      if (policy[r] > 0.0) b[s] += policy[r] * reward[r];
    }
  }
  PolicyMatrix matrix(mdp);
  matrix.set_policy(policy);
  return solve_policy(matrix, b, guess);
}

}  // namespace hbirl
