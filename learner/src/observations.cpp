#include "learner/observations.hpp"

#include <algorithm>
#include <string>
#include <limits>
#include <cmath>
#include <map>
#include <numeric>

#include "learner/digest.hpp"
#include "learner/input_error.hpp"

namespace hbirl {

std::uint64_t dataset_digest(std::span<const ObservedTrajectory> trajectories) {
  Fnv1a h;
  h.add(static_cast<std::uint64_t>(trajectories.size()));
  for (const auto& t : trajectories) {
    h.add(static_cast<std::uint64_t>(t.step_begin.size()));
    h.add(t.step_begin.data(), t.step_begin.size() * sizeof(int));
    h.add(static_cast<std::uint64_t>(t.symbols.size()));
    h.add(t.symbols.data(), t.symbols.size() * sizeof(int));
    h.add(static_cast<std::int64_t>(t.eta.rows()));
    h.add(static_cast<std::int64_t>(t.eta.cols()));
    h.add(t.eta.data(), static_cast<size_t>(t.eta.size()) * sizeof(double));
    h.add(static_cast<std::uint64_t>(t.weights.size()));
    h.add(t.weights.data(), t.weights.size() * sizeof(double));
    h.add(static_cast<unsigned char>(t.ends_in_terminal));
    if (t.end_state >= 0) h.add(static_cast<std::int64_t>(t.end_state));  // digests without it unchanged
    if (!t.end_symbols.empty()) {
      h.add(static_cast<std::uint64_t>(t.end_symbols.size()));
      h.add(t.end_symbols.data(), t.end_symbols.size() * sizeof(int));
    }
    if (!t.contexts.empty()) {
      h.add(static_cast<std::uint64_t>(t.contexts.size()));
      h.add(t.contexts.data(), t.contexts.size() * sizeof(int));
    }
  }
  return h.value();
}

Eigen::VectorXd end_log_evidence(const Mdp& mdp, const ObservedTrajectory& trajectory,
                                 const Eigen::MatrixXd& end_model) {
  const int S = mdp.num_states;
  if (!trajectory.ends_in_terminal) {
    if (!trajectory.end_symbols.empty())
      throw InputError("end_symbols", "given, but the trajectory does not end in a terminal state");
    return Eigen::VectorXd::Zero(S);
  }
  const int seen = trajectory.end_state;
  if (seen >= 0 && (seen >= S || !mdp.is_terminal(seen)))
    throw InputError("end_state", std::to_string(seen) + " is not a terminal state");
  if (!trajectory.end_symbols.empty() && end_model.rows() != S)
    throw InputError("end_symbols", "given, but there is no end sensor (no end_alpha)");
  for (int w : trajectory.end_symbols) {
    if (w < 0 || w >= end_model.cols())
      throw InputError("end_symbols", std::to_string(w) + " is not a symbol of the end sensor (it has " +
                                          std::to_string(end_model.cols()) + ")");
  }
  Eigen::VectorXd out = Eigen::VectorXd::Constant(S, kNegInf);
  for (int s = 0; s < S; ++s) {
    if (!mdp.is_terminal(s) || (seen >= 0 && s != seen)) continue;
    double sum = 0.0;
    for (int w : trajectory.end_symbols) sum += std::log(end_model(s, w));  // log 0 = -inf: impossible there
    out[s] = sum;
  }
  return out;
}

Eigen::VectorXd shifted_exp(const Eigen::VectorXd& v, double* top) {
  const double m = v.size() > 0 ? v.maxCoeff() : kNegInf;
  if (top) *top = m;
  Eigen::VectorXd out = Eigen::VectorXd::Zero(v.size());
  if (m == kNegInf) return out;
  for (Eigen::Index i = 0; i < v.size(); ++i) out[i] = v[i] == kNegInf ? 0.0 : std::exp(v[i] - m);
  return out;
}

bool every_observation_has_context(std::span<const ObservedTrajectory> trajectories) {
  bool any = false;
  for (const ObservedTrajectory& t : trajectories) {
    if (t.contexts.size() != t.symbols.size()) return false;
    any = any || !t.symbols.empty();
  }
  return any;
}

std::string normalise_eta(double* eta, int n, double tolerance) {
  if (n < 1) return "is empty";
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(eta[i]) || eta[i] < 0.0) return "entry " + std::to_string(i) + " is not a probability";
    sum += eta[i];
  }
  if (!(std::abs(sum - 1.0) <= tolerance)) return "sums to " + std::to_string(sum) + ", expected 1";
  if (std::abs(sum - 1.0) > 8.0 * n * std::numeric_limits<double>::epsilon()) {
    for (int i = 0; i < n; ++i) eta[i] /= sum;
  }
  return "";
}

ObservedTrajectory merge_identical_observations(const ObservedTrajectory& trajectory, std::vector<int>* merged_of) {
  ObservedTrajectory out;
  out.ends_in_terminal = trajectory.ends_in_terminal;
  out.end_state = trajectory.end_state;
  out.end_symbols = trajectory.end_symbols;
  const Eigen::Index sources = trajectory.eta.cols();
  std::vector<int> rows;
  std::vector<double> weights;
  auto less = [&](int x, int y) {
    if (trajectory.symbols[static_cast<size_t>(x)] != trajectory.symbols[static_cast<size_t>(y)]) {
      return trajectory.symbols[static_cast<size_t>(x)] < trajectory.symbols[static_cast<size_t>(y)];
    }
    for (Eigen::Index z = 0; z < sources; ++z) {
      if (trajectory.eta(x, z) != trajectory.eta(y, z)) return trajectory.eta(x, z) < trajectory.eta(y, z);
    }
    // Context last: contexts given later as a function of eta (learned eta numbers each
    // distinct eta) keep the order, so merging again is the identity -- what a worker
    // holding a share of the merged data relies on.
    return trajectory.context(x) < trajectory.context(y);
  };
  if (merged_of) merged_of->assign(static_cast<size_t>(trajectory.num_observations()), -1);
  for (int t = 0; t < trajectory.length(); ++t) {
    std::vector<int> step(static_cast<size_t>(trajectory.observations_at(t)));
    std::iota(step.begin(), step.end(), trajectory.step_begin[static_cast<size_t>(t)]);
    std::sort(step.begin(), step.end(), less);
    for (size_t i = 0; i < step.size(); ++i) {
      if (i > 0 && !less(step[i - 1], step[i])) {
        weights.back() += trajectory.weight(step[i]);
      } else {
        rows.push_back(step[i]);
        weights.push_back(trajectory.weight(step[i]));
      }
      if (merged_of) (*merged_of)[static_cast<size_t>(step[i])] = static_cast<int>(rows.size()) - 1;
    }
    out.step_begin.push_back(static_cast<int>(rows.size()));
  }
  out.eta.resize(static_cast<Eigen::Index>(rows.size()), sources);
  for (size_t i = 0; i < rows.size(); ++i) {
    out.symbols.push_back(trajectory.symbols[static_cast<size_t>(rows[i])]);
    out.eta.row(static_cast<Eigen::Index>(i)) = trajectory.eta.row(rows[i]);
    if (!trajectory.contexts.empty()) out.contexts.push_back(trajectory.context(rows[i]));
  }
  out.weights = std::move(weights);
  return out;
}

std::optional<ObservationKinds> observation_kinds(const std::vector<ObservedTrajectory>& trajectories, int max_kinds) {
  ObservationKinds kinds;
  // Key: the symbol, then eta's entries bit for bit (set up once per data set, not in a loop
  // of the E-step).
  std::map<std::vector<double>, int> index;
  std::vector<std::vector<double>> rows;
  for (const auto& t : trajectories) {
    std::vector<int>& of = kinds.of.emplace_back(static_cast<size_t>(t.num_observations()));
    for (int n = 0; n < t.num_observations(); ++n) {
      std::vector<double> key(static_cast<size_t>(t.eta.cols()) + 2);
      key[0] = t.symbols[static_cast<size_t>(n)];
      key[1] = t.context(n);
      for (Eigen::Index z = 0; z < t.eta.cols(); ++z) key[static_cast<size_t>(z) + 2] = t.eta(n, z);
      const auto [it, inserted] = index.emplace(std::move(key), static_cast<int>(rows.size()));
      if (inserted) {
        if (static_cast<int>(rows.size()) >= max_kinds) return std::nullopt;
        rows.push_back(it->first);
      }
      of[static_cast<size_t>(n)] = it->second;
    }
  }
  const Eigen::Index sources = rows.empty() ? 0 : static_cast<Eigen::Index>(rows[0].size()) - 2;
  kinds.eta.resize(static_cast<Eigen::Index>(rows.size()), sources);
  for (size_t k = 0; k < rows.size(); ++k) {
    kinds.symbols.push_back(static_cast<int>(rows[k][0]));
    kinds.contexts.push_back(static_cast<int>(rows[k][1]));
    for (Eigen::Index z = 0; z < sources; ++z)
      kinds.eta(static_cast<Eigen::Index>(k), z) = rows[k][static_cast<size_t>(z) + 2];
  }
  return kinds;
}

void add_unlisted_source(ObservationPrior& prior, std::vector<ObservedTrajectory>& trajectories) {
  const double epsilon = prior.unlisted_eta;
  if (!adds_unlisted_source(prior)) return;
  if (!(epsilon > 0.0 && epsilon < 1.0)) throw InputError("observation_model.unlisted_source.eta", "must be in (0, 1)");
  const Eigen::Index sources = 1 + prior.num_confounders;
  for (auto& t : trajectories) {
    if (t.num_observations() > 0 && t.eta.cols() != sources) {
      throw InputError("demonstration", "eta has " + std::to_string(t.eta.cols()) + " sources, the observation model " +
                                            std::to_string(sources));
    }
    RowMatrix eta(t.eta.rows(), sources + 1);
    if (t.num_observations() == 0) {  // its eta may have any number of columns (none to scale)
      t.eta = std::move(eta);
      continue;
    }
    eta.leftCols(sources) = (1.0 - epsilon) * t.eta;
    eta.col(sources).setConstant(epsilon);
    // Rows that rounding took past normalise_eta's tolerance are brought back, so that a
    // reader that normalises (a sampler worker receiving the data set) keeps their bits.
    for (Eigen::Index n = 0; n < eta.rows(); ++n) normalise_eta(eta.row(n).data(), static_cast<int>(sources + 1));
    t.eta = std::move(eta);
  }
  Eigen::MatrixXd confounders(prior.num_confounders + 1, prior.num_symbols);
  confounders.topRows(prior.num_confounders) = prior.confounder_alpha;
  confounders.row(prior.num_confounders).setOnes();  // flat: nothing is known of it
  prior.confounder_alpha = std::move(confounders);
  ++prior.num_confounders;
  prior.unlisted_added = true;
}

void use_alpha_update(ObservationPrior& prior, AlphaUpdate update) {
  prior.update = update;
  prior.learn_eta = update == AlphaUpdate::kPosterior;
}

const char* alpha_update_name(AlphaUpdate update) { return update == AlphaUpdate::kPaper ? "paper" : "posterior"; }

bool parse_alpha_update(const std::string& name, AlphaUpdate& update) {
  if (name == "posterior") {
    update = AlphaUpdate::kPosterior;
  } else if (name == "paper") {
    update = AlphaUpdate::kPaper;
  } else {
    return false;
  }
  return true;
}

}  // namespace hbirl
