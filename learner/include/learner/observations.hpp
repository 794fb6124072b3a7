#pragma once
// What the sensors give the learner (SPEC §1): at timestep t, N_t >= 0 observations,
// each a symbol omega in Omega = {0 .. num_symbols-1} with a source distribution eta over
// 1 + |E| sources (index 0 the subject, 1..|E| the confounding elements). N_t = 0 is
// occlusion. Stored flat, one row per observation, so an E-step streams through memory.
#include <Eigen/Core>
#include <optional>
#include <cstdint>
#include <vector>

namespace hbirl {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct ObservedTrajectory {
  std::vector<int> step_begin{0};  // observations of step t are rows [step_begin[t], step_begin[t+1])
  std::vector<int> symbols;        // one per observation
  RowMatrix eta;                   // one row per observation, 1 + |E| columns
  // Optional multiplicities: observation n stands for weights[n] identical ones (see
  // merge_identical_observations). Empty means every weight is 1.
  std::vector<double> weights;
  // The trajectory ended because its last action led into a terminal state (rather than
  // being cut off): the posterior then conditions on that.
  bool ends_in_terminal = false;

  int length() const { return static_cast<int>(step_begin.size()) - 1; }
  int num_observations() const { return static_cast<int>(symbols.size()); }
  int observations_at(int t) const {
    return step_begin[static_cast<size_t>(t) + 1] - step_begin[static_cast<size_t>(t)];
  }
  double weight(int n) const { return weights.empty() ? 1.0 : weights[static_cast<size_t>(n)]; }
};

// A 64-bit digest (FNV-1a) of a data set: every length, symbol, eta and weight, bit for
// bit. Two processes with the same digest hold the same data (services/ compares them).
std::uint64_t dataset_digest(const std::vector<ObservedTrajectory>& trajectories);

// The same trajectory with identical (symbol, eta) observations of a step merged into
// one with a multiplicity: an exact rewrite of the emission product that makes the
// E-step's cost grow with the number of distinct observations, not all of them.
ObservedTrajectory merge_identical_observations(const ObservedTrajectory& trajectory);

// The distinct (symbol, eta) observations of a data set ("kinds"), and the kind of every
// observation row. When eta takes few values (a labeller's rules, uniform eta) a data set
// of millions of observations has a few dozen kinds, and the E-step computes each kind's
// emission p(w | s,a) once per pass instead of once per observation.
struct ObservationKinds {
  std::vector<int> symbols;             // per kind
  RowMatrix eta;                        // per kind
  std::vector<std::vector<int>> of;     // per trajectory, per observation row: its kind
  int num_kinds() const { return static_cast<int>(symbols.size()); }
};

// The kinds of `trajectories`, or nothing when there are more than `max_kinds`.
std::optional<ObservationKinds> observation_kinds(const std::vector<ObservedTrajectory>& trajectories, int max_kinds);

// Dirichlet priors of the observation model (SPEC §1): alpha for the subject's
// O_{s,a} (one row per (s, a) pair) and for each confounding element's O_e.
struct ObservationPrior {
  int num_symbols = 0;
  int num_confounders = 0;
  Eigen::MatrixXd subject_alpha;     // (S*A) x num_symbols
  Eigen::MatrixXd confounder_alpha;  // num_confounders x num_symbols
  bool learn = true;                 // refine alpha inside the E-step (paper Algorithm 1)
  double c = 0.1;                    // alpha_i = c * alpha_dot + (1 - c) * alpha_{i-1}
};

}  // namespace hbirl
