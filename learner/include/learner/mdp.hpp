#pragma once
// A discrete MDP <S, A, T, R = theta . phi> (paper §II; docs/MODEL.md "MDP conventions").
//
// Rows of the transition and feature matrices are indexed by the state-action pair
// r = s * num_actions + a. Transitions are sparse (CSR: Eigen's row-major sparse
// matrix, one row per (s, a), one column per next state). An (s, a) row with no
// entries is an impossible action: it gets Q = -inf and probability 0.
//
// Terminal states end a trajectory when it enters them: they are never occupied at a
// timestep, take no action, collect no reward and have value 0.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <limits>
#include <vector>

namespace hbirl {

using SparseRowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

// log 0: an impossible action's Q and log-probability, a never-occupied state's.
inline constexpr double kNegInf = -std::numeric_limits<double>::infinity();
// The largest discount (an effective horizon 1/(1 - gamma) of 10^6 steps): closer to 1,
// the soft Bellman backups contract too slowly to converge in double precision and a
// solve spins (docs/RELIABILITY.md).
inline constexpr double kMaxDiscount = 0.999999;
// The largest feature value (and true weight) in magnitude: rewards and values stay far
// from overflow whatever weights the optimiser tries. Features are meant to be of order 1.
inline constexpr double kMaxFeatureMagnitude = 1e6;

struct TransitionEntry {
  int state;
  int action;
  int next_state;
  double probability;
};

struct FeatureEntry {
  int state;
  int action;
  int feature;
  double value;
};

struct Mdp {
  int num_states = 0;
  int num_actions = 0;
  SparseRowMatrix transitions;  // (S*A) x S
  Eigen::MatrixXd features;     // (S*A) x K
  Eigen::VectorXd start;        // S, a distribution over non-terminal states
  std::vector<char> terminal;   // S, 1 = terminal
  double discount = 0.95;

  int num_features() const { return static_cast<int>(features.cols()); }
  int num_pairs() const { return num_states * num_actions; }
  int pair(int s, int a) const { return s * num_actions + a; }
  bool is_terminal(int s) const { return terminal[static_cast<size_t>(s)] != 0; }
  bool available(int s, int a) const {
    const int r = pair(s, a);
    return transitions.outerIndexPtr()[r + 1] > transitions.outerIndexPtr()[r];
  }

  // R(s,a) = theta . phi(s,a), one entry per (s, a) pair.
  Eigen::VectorXd reward(const Eigen::VectorXd& theta) const;

  // Throws InputError naming the first violated property: sizes, probabilities that
  // are negative, NaN/inf or do not sum to 1 per available (s, a), start mass on
  // terminal states, non-terminal states with no available action, discount outside
  // [0, 1), non-finite features.
  void validate() const;
};

// A digest of the dynamics -- sizes, transitions, start, terminal states, discount; not the
// features -- which is what an E-step computes with (the reward reaches it as a policy).
std::uint64_t dynamics_digest(const Mdp& mdp);

// Builds an MDP from entry lists (duplicate transition entries are summed).
// Indices are checked; call validate() for the probabilistic properties.
Mdp make_mdp(int num_states, int num_actions, int num_features, const std::vector<TransitionEntry>& transitions,
             const std::vector<FeatureEntry>& features, const Eigen::VectorXd& start,
             const std::vector<int>& terminal_states, double discount);

}  // namespace hbirl
