#include "learner/mdp.hpp"

#include <cmath>
#include <string>

#include "learner/digest.hpp"
#include "learner/input_error.hpp"

namespace hbirl {

std::uint64_t dynamics_digest(const Mdp& mdp) {
  Fnv1a h;
  h.add(mdp.num_states);
  h.add(mdp.num_actions);
  h.add(mdp.discount);
  h.add(static_cast<std::int64_t>(mdp.transitions.nonZeros()));
  h.add(mdp.transitions.outerIndexPtr(), static_cast<size_t>(mdp.transitions.outerSize() + 1) * sizeof(int));
  h.add(mdp.transitions.innerIndexPtr(), static_cast<size_t>(mdp.transitions.nonZeros()) * sizeof(int));
  h.add(mdp.transitions.valuePtr(), static_cast<size_t>(mdp.transitions.nonZeros()) * sizeof(double));
  h.add(mdp.start.data(), static_cast<size_t>(mdp.start.size()) * sizeof(double));
  h.add(mdp.terminal.data(), mdp.terminal.size());
  return h.value();
}

namespace {
constexpr double kSumTolerance = 1e-9;

std::string pair_name(int s, int a) { return "(s=" + std::to_string(s) + ", a=" + std::to_string(a) + ")"; }
}  // namespace

Eigen::VectorXd Mdp::reward(const Eigen::VectorXd& theta) const {
  if (theta.size() != features.cols()) {
    throw InputError("weights",
                     "has " + std::to_string(theta.size()) + " entries, expected " + std::to_string(features.cols()));
  }
  return features * theta;
}

void Mdp::validate() const {
  if (num_states <= 0) throw InputError("mdp.num_states", "must be positive");
  if (num_actions <= 0) throw InputError("mdp.num_actions", "must be positive");
  if (transitions.rows() != num_pairs() || transitions.cols() != num_states) {
    throw InputError("mdp.transitions", "matrix has the wrong shape");
  }
  if (features.rows() != num_pairs()) throw InputError("mdp.features", "matrix has the wrong shape");
  if (start.size() != num_states) throw InputError("mdp.start", "has the wrong length");
  if (terminal.size() != static_cast<size_t>(num_states)) {
    throw InputError("mdp.terminal", "has the wrong length");
  }
  if (!(discount >= 0.0 && discount < 1.0)) {
    throw InputError("mdp.discount", "must be in [0, 1), got " + std::to_string(discount));
  }
  if (discount > kMaxDiscount) {
    throw InputError("mdp.discount",
                     "must be at most 0.999999 (a horizon 1/(1 - discount) of a million steps); value "
                     "iteration cannot converge closer to 1");
  }
  const int* outer = transitions.outerIndexPtr();
  const int* inner = transitions.innerIndexPtr();
  const double* value = transitions.valuePtr();
  for (int s = 0; s < num_states; ++s) {
    int available_actions = 0;
    for (int a = 0; a < num_actions; ++a) {
      const int r = pair(s, a);
      double sum = 0.0;
      for (int j = outer[r]; j < outer[r + 1]; ++j) {
        if (inner[j] < 0 || inner[j] >= num_states) {
          throw InputError("mdp.transitions",
                           pair_name(s, a) + ": next state " + std::to_string(inner[j]) + " out of range");
        }
        if (!std::isfinite(value[j]) || value[j] < 0.0) {
          throw InputError("mdp.transitions", pair_name(s, a) + ": probability " + std::to_string(value[j]) +
                                                  " is not a finite non-negative number");
        }
        sum += value[j];
      }
      if (outer[r + 1] > outer[r]) {
        ++available_actions;
        if (std::abs(sum - 1.0) > kSumTolerance) {
          throw InputError("mdp.transitions",
                           pair_name(s, a) + ": probabilities sum to " + std::to_string(sum) + ", expected 1");
        }
      }
    }
    if (available_actions == 0 && !is_terminal(s)) {
      throw InputError("mdp.transitions",
                       "state " + std::to_string(s) + " is not terminal but has no available action");
    }
  }
  if (!features.allFinite()) throw InputError("mdp.features", "contains NaN or inf");
  if (features.size() > 0 && features.cwiseAbs().maxCoeff() > kMaxFeatureMagnitude) {
    throw InputError("mdp.features",
                     "has a value beyond +-1e6: rescale the features (they are meant to be of order 1)");
  }
  double start_sum = 0.0;
  for (int s = 0; s < num_states; ++s) {
    if (!std::isfinite(start[s]) || start[s] < 0.0) {
      throw InputError("mdp.start",
                       "probability of state " + std::to_string(s) + " is not a finite non-negative number");
    }
    if (start[s] > 0.0 && is_terminal(s)) {
      throw InputError("mdp.start", "state " + std::to_string(s) + " is terminal");
    }
    start_sum += start[s];
  }
  if (std::abs(start_sum - 1.0) > kSumTolerance) {
    throw InputError("mdp.start", "probabilities sum to " + std::to_string(start_sum) + ", expected 1");
  }
}

Mdp make_mdp(int num_states, int num_actions, int num_features, const std::vector<TransitionEntry>& transitions,
             const std::vector<FeatureEntry>& features, const Eigen::VectorXd& start,
             const std::vector<int>& terminal_states, double discount) {
  if (num_states <= 0) throw InputError("mdp.num_states", "must be positive");
  if (num_actions <= 0) throw InputError("mdp.num_actions", "must be positive");
  if (num_features < 0) throw InputError("mdp.num_features", "must be non-negative");
  Mdp mdp;
  mdp.num_states = num_states;
  mdp.num_actions = num_actions;
  mdp.discount = discount;
  std::vector<Eigen::Triplet<double, int>> triplets;
  triplets.reserve(transitions.size());
  for (size_t i = 0; i < transitions.size(); ++i) {
    const auto& t = transitions[i];
    const std::string field = "mdp.transitions[" + std::to_string(i) + "]";
    if (t.state < 0 || t.state >= num_states) throw InputError(field, "state out of range");
    if (t.action < 0 || t.action >= num_actions) throw InputError(field, "action out of range");
    if (t.next_state < 0 || t.next_state >= num_states) {
      throw InputError(field, "next state out of range");
    }
    triplets.emplace_back(mdp.pair(t.state, t.action), t.next_state, t.probability);
  }
  mdp.transitions.resize(mdp.num_pairs(), num_states);
  mdp.transitions.setFromTriplets(triplets.begin(), triplets.end());
  mdp.transitions.makeCompressed();
  mdp.features = Eigen::MatrixXd::Zero(mdp.num_pairs(), num_features);
  for (size_t i = 0; i < features.size(); ++i) {
    const auto& f = features[i];
    const std::string field = "mdp.features[" + std::to_string(i) + "]";
    if (f.state < 0 || f.state >= num_states) throw InputError(field, "state out of range");
    if (f.action < 0 || f.action >= num_actions) throw InputError(field, "action out of range");
    if (f.feature < 0 || f.feature >= num_features) throw InputError(field, "feature out of range");
    mdp.features(mdp.pair(f.state, f.action), f.feature) = f.value;
  }
  mdp.start = start;
  mdp.terminal.assign(static_cast<size_t>(num_states), 0);
  for (int s : terminal_states) {
    if (s < 0 || s >= num_states) throw InputError("mdp.terminal", "state out of range");
    mdp.terminal[static_cast<size_t>(s)] = 1;
  }
  return mdp;
}

}  // namespace hbirl
