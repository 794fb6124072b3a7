#include "learner/controlled_prior.hpp"

#include <cmath>

#include "learner/input_error.hpp"

namespace hbirl {
namespace {

// The steps' slices of the observations, and their multiplicities, are what the counts
// index by: check them before reading.
void check_layout(const ObservedTrajectory& o) {
  const std::vector<int>& begin = o.step_begin;
  if (begin.empty() || begin.front() != 0) throw InputError("observations.step_begin", "must start at 0");
  for (size_t t = 1; t < begin.size(); ++t) {
    if (begin[t] < begin[t - 1]) throw InputError("observations.step_begin", "decreases");
  }
  if (static_cast<size_t>(begin.back()) != o.symbols.size()) {
    throw InputError("observations.step_begin", "does not end at the number of observations");
  }
  if (!o.weights.empty() && o.weights.size() != o.symbols.size()) {
    throw InputError("observations.weights", "not one per observation");
  }
  for (double w : o.weights) {
    if (!std::isfinite(w) || w < 0.0) throw InputError("observations.weights", "must be finite and non-negative");
  }
}

void check_controlled_run(const Mdp& mdp, const std::vector<Trajectory>& truth,
                          const std::vector<ObservedTrajectory>& observed, int num_symbols) {
  if (num_symbols <= 0) throw InputError("observations.num_symbols", "must be positive");
  if (truth.size() != observed.size())
    throw InputError("ground_truth", "not one trajectory of true steps per controlled episode");
  for (size_t i = 0; i < truth.size(); ++i) {
    if (static_cast<int>(truth[i].size()) != observed[i].length())
      throw InputError("ground_truth", "steps differ from the episode's");
    for (const StateAction& x : truth[i]) {
      if (x.state < 0 || x.state >= mdp.num_states || x.action < 0 || x.action >= mdp.num_actions) {
        throw InputError("ground_truth", "state or action outside the domain");
      }
    }
    check_layout(observed[i]);
    for (int w : observed[i].symbols) {
      if (w < 0 || w >= num_symbols) throw InputError("observations.symbols", "symbol outside the domain's");
    }
  }
}

}  // namespace

Eigen::MatrixXd controlled_run_prior(const Mdp& mdp, const std::vector<Trajectory>& truth,
                                     const std::vector<ObservedTrajectory>& observed, int num_symbols,
                                     const ControlledPriorOptions& options) {
  check_controlled_run(mdp, truth, observed, num_symbols);
  Eigen::MatrixXd counts = Eigen::MatrixXd::Zero(mdp.num_pairs(), num_symbols);
  Eigen::VectorXd visits = Eigen::VectorXd::Zero(mdp.num_pairs());
  for (size_t i = 0; i < truth.size(); ++i) {
    const ObservedTrajectory& o = observed[i];
    for (int t = 0; t < o.length(); ++t) {
      const StateAction& x = truth[i][static_cast<size_t>(t)];
      const int r = mdp.pair(x.state, x.action);
      visits[r] += 1.0;
      for (int n = o.step_begin[static_cast<size_t>(t)]; n < o.step_begin[static_cast<size_t>(t) + 1]; ++n) {
        counts(r, o.symbols[static_cast<size_t>(n)]) += o.weight(n);
      }
    }
  }
  if (options.per_visit) {
    for (int r = 0; r < mdp.num_pairs(); ++r) {
      if (visits[r] > 0.0) counts.row(r) /= visits[r];
    }
  }
  return counts.array() + options.pseudo_count;
}

}  // namespace hbirl
