#include "services/estep_wire.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "learner/digest.hpp"
#include "learner/input_error.hpp"
#include "learner/soft_value_iteration.hpp"
#include "services/lcm_arrays.hpp"

namespace hbirl::services {

std::uint64_t numerics_fingerprint() {
  static const std::uint64_t fingerprint = [] {
    // Four states in a ring, two actions (stay, or move on with probability 0.7), two
    // symbols, one confounding element, two short observed trajectories.
    std::vector<TransitionEntry> transitions;
    for (int s = 0; s < 4; ++s) {
      transitions.push_back({s, 0, s, 1.0});
      transitions.push_back({s, 1, (s + 1) % 4, 0.7});
      transitions.push_back({s, 1, s, 0.3});
    }
    const Mdp mdp =
        make_mdp(4, 2, 1, transitions, {{1, 1, 0, 1.0}, {3, 0, 0, 0.5}}, Eigen::Vector4d(0.4, 0.3, 0.2, 0.1), {}, 0.9);
    std::vector<ObservedTrajectory> observed(2);
    const int symbols[2][6] = {{0, 1, 1, 0, 1, 0}, {1, 1, 0, 0, 0, 1}};
    for (int i = 0; i < 2; ++i) {
      observed[static_cast<size_t>(i)].eta.resize(6, 2);
      for (int k = 0; k < 6; ++k) {
        observed[static_cast<size_t>(i)].symbols.push_back(symbols[i][k]);
        observed[static_cast<size_t>(i)].eta.row(k) << 0.3 + 0.1 * k, 0.7 - 0.1 * k;
        if (k % 2 == 1) observed[static_cast<size_t>(i)].step_begin.push_back(k + 1);
      }
    }
    ObservationPrior prior;
    prior.num_symbols = 2;
    prior.num_confounders = 1;
    prior.subject_alpha = Eigen::MatrixXd::Constant(8, 2, 0.5);
    prior.subject_alpha.col(0).array() += Eigen::ArrayXd::LinSpaced(8, 0.1, 3.0);
    prior.confounder_alpha = Eigen::MatrixXd::Ones(1, 2);
    const ObservationEStep estep(mdp, observed, prior, {});
    const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(Eigen::VectorXd::Constant(1, 1.3)));
    const EStepStatistics stats = estep.block_statistics(policy, dirichlet_mean(prior), 1, {0}).front();
    Fnv1a h;  // over the bits of every result
    const auto mix = [&h](const double* x, Eigen::Index n) { h.add(x, static_cast<size_t>(n) * sizeof(double)); };
    mix(policy.log_policy.data(), policy.log_policy.size());
    mix(stats.counts.data(), stats.counts.size());
    mix(stats.alpha_dot.subject.data(), stats.alpha_dot.subject.size());
    mix(stats.alpha_dot.confounders.data(), stats.alpha_dot.confounders.size());
    mix(&stats.log_likelihood, 1);
    return h.value();
  }();
  return fingerprint;
}

hbirl::trajectory_t to_message(const ObservedTrajectory& t, int index, int count, std::uint64_t block_digest,
                               const std::string& worker) {
  hbirl::trajectory_t m{};
  m.utime = 0;  // a data set, not a moment of the demonstration
  m.block_digest = static_cast<std::int64_t>(block_digest);
  m.index = index;
  m.num_trajectories = count;
  m.block_size = ObservationEStep::kBlockSize;
  m.worker = worker;
  m.episode = index;
  m.ends_in_terminal = t.ends_in_terminal;
  m.num_steps = t.length();
  m.step_begin.assign(t.step_begin.begin(), t.step_begin.end() - 1);
  m.n = t.num_observations();
  for (int s : t.symbols) m.symbol.push_back(static_cast<std::int16_t>(s));
  m.num_sources = static_cast<std::int32_t>(t.eta.cols());
  m.eta = lcm_rows(t.eta);
  m.num_weights = static_cast<std::int32_t>(t.weights.size());
  m.weights = t.weights;
  m.num_context = static_cast<std::int32_t>(t.contexts.size());
  m.context = t.contexts;
  m.end_state_known = t.end_state >= 0;
  m.end_state = std::max(t.end_state, 0);
  m.num_end_reports = static_cast<std::int32_t>(t.end_symbols.size());
  for (int w : t.end_symbols) m.end_report.push_back(static_cast<std::int16_t>(w));
  return m;
}

ObservedTrajectory from_message(const hbirl::trajectory_t& m) {
  if (m.num_steps < 1) throw InputError("trajectory.num_steps", "must be at least 1");
  if (m.n < 0) throw InputError("trajectory.n", "is negative");
  if (m.num_sources < 1) throw InputError("trajectory.num_sources", "must be at least 1 (the subject)");
  ObservedTrajectory t;
  t.step_begin.assign(m.step_begin.begin(), m.step_begin.end());
  t.step_begin.push_back(m.n);
  if (t.step_begin.front() != 0) throw InputError("trajectory.step_begin[0]", "must be 0");
  for (size_t i = 1; i < t.step_begin.size(); ++i) {
    if (t.step_begin[i] < t.step_begin[i - 1]) {
      throw InputError("trajectory.step_begin[" + std::to_string(i) + "]", "goes backwards or past the observations");
    }
  }
  for (int i = 0; i < m.n; ++i) {
    if (m.symbol[static_cast<size_t>(i)] < 0)
      throw InputError("trajectory.symbol[" + std::to_string(i) + "]", "is negative");
    t.symbols.push_back(m.symbol[static_cast<size_t>(i)]);
  }
  t.eta = eigen_rows<RowMatrix>(m.eta, m.num_sources);
  for (int i = 0; i < m.n; ++i) {
    const std::string wrong = normalise_eta(t.eta.row(i).data(), m.num_sources);
    if (!wrong.empty()) throw InputError("trajectory.eta[" + std::to_string(i) + "]", wrong);
  }
  if (m.num_weights != 0 && m.num_weights != m.n) throw InputError("trajectory.num_weights", "must be 0 or n");
  for (double w : m.weights) {
    if (!(std::isfinite(w) && w > 0.0)) throw InputError("trajectory.weights", "must be finite and > 0");
  }
  t.weights = m.weights;
  if (m.num_context != 0 && m.num_context != m.n) throw InputError("trajectory.num_context", "must be 0 or n");
  for (int c : m.context) {
    if (c < 0 || c >= kMaxContexts)
      throw InputError("trajectory.context",
                       std::to_string(c) + " is outside [0, " + std::to_string(kMaxContexts - 1) + "]");
  }
  t.contexts = m.context;
  t.ends_in_terminal = m.ends_in_terminal;
  // What was seen of the end: its states and symbols are checked against the MDP and the
  // end sensor where the worker builds its E-step (ObservationEStep).
  if (m.end_state_known) {
    if (m.end_state < 0) throw InputError("trajectory.end_state", "is negative");
    t.end_state = m.end_state;
  }
  if (m.num_end_reports < 0) throw InputError("trajectory.num_end_reports", "is negative");
  t.end_symbols.assign(m.end_report.begin(), m.end_report.end());
  return t;
}

std::span<const ObservedTrajectory> block_of(const std::vector<ObservedTrajectory>& trajectories, int b) {
  const auto begin = static_cast<size_t>(b) * ObservationEStep::kBlockSize;
  return std::span<const ObservedTrajectory>(trajectories)
      .subspan(begin, std::min<size_t>(ObservationEStep::kBlockSize, trajectories.size() - begin));
}

hbirl::estep_request_t request_message(const PassData& pass, const ObservationEStep& estep, const SoftSolution& policy,
                                       const ObservationModel& model, const RowMatrix* eta) {
  hbirl::estep_request_t request{};
  request.utime = 0;
  request.request_id = pass.request_id;
  request.dataset_digest = static_cast<std::int64_t>(pass.data_digest);
  request.mdp_digest = static_cast<std::int64_t>(pass.mdp_digest);
  request.num_trajectories = static_cast<std::int32_t>(estep.trajectories().size());
  request.block_size = ObservationEStep::kBlockSize;
  request.num_blocks = estep.num_blocks();
  for (const std::uint64_t d : *pass.block_digests) request.block_digest.push_back(static_cast<std::int64_t>(d));
  request.kind_table = estep.uses_kind_table();
  request.seed = static_cast<std::int64_t>(pass.seed);
  request.engine = "exact";
  request.max_kinds = estep.options().max_kinds;
  request.watch = estep.options().watch;
  request.num_pairs = estep.mdp().num_pairs();
  request.log_policy = lcm_vector(policy.log_policy);
  request.policy = lcm_vector(policy.policy);
  request.num_symbols = model.num_symbols();
  request.num_confounders = model.num_confounders();
  request.subject_o = lcm_rows(model.subject);
  request.confounder_o = lcm_rows(model.confounders);
  request.num_contexts = eta ? static_cast<std::int32_t>(eta->rows()) : 0;
  request.num_sources = 1 + model.num_confounders();
  if (eta) request.context_eta = lcm_rows(*eta);
  request.num_end_rows = static_cast<std::int32_t>(model.end.rows());
  request.num_end_symbols = static_cast<std::int32_t>(model.end.cols());
  request.end_o = lcm_rows(model.end);
  return request;
}

void check_shape(const hbirl::estep_result_t& m, const ResultShape& shape) {
  if (m.num_pairs != shape.pairs || m.num_symbols != shape.symbols || m.num_confounders != shape.confounders) {
    throw InputError("estep_result.num_pairs", "the statistics have the wrong shape");
  }
  // End counts exactly from the blocks whose trajectories have end reports, in O_end's shape.
  const bool reported =
      static_cast<size_t>(m.block) < shape.end_reported.size() && shape.end_reported[static_cast<size_t>(m.block)];
  if (m.num_end_rows != (reported ? shape.end_rows : 0) || (reported && m.num_end_symbols != shape.end_symbols))
    throw InputError("estep_result.num_end_rows", "the end sensor's counts have the wrong shape for this block");
  if (!std::isfinite(m.log_likelihood) && m.log_likelihood != -std::numeric_limits<double>::infinity()) {
    throw InputError("estep_result.log_likelihood", "is NaN or +inf");
  }
}

EStepStatistics statistics_of(const hbirl::estep_result_t& m, const ResultShape& shape) {
  const int pairs = shape.pairs, symbols = shape.symbols, confounders = shape.confounders, contexts = shape.contexts;
  EStepStatistics s = EStepStatistics::zero(pairs, confounders, symbols, contexts);
  s.counts = eigen_vector(m.counts);
  s.alpha_dot.subject = eigen_rows(m.alpha_subject, symbols);
  s.alpha_dot.confounders = eigen_rows(m.alpha_confounder, symbols);
  if (!s.counts.allFinite() || !s.alpha_dot.subject.allFinite() || !s.alpha_dot.confounders.allFinite() ||
      (s.counts.array() < 0).any() || (s.alpha_dot.subject.array() < 0).any() ||
      (s.alpha_dot.confounders.array() < 0).any()) {
    throw InputError("estep_result.counts", "must be finite and >= 0");
  }
  if (m.num_end_rows > 0) {
    s.alpha_dot.end = eigen_rows(m.alpha_end, m.num_end_symbols);
    if (!s.alpha_dot.end.allFinite() || (s.alpha_dot.end.array() < 0).any())
      throw InputError("estep_result.alpha_end", "must be finite and >= 0");
  }
  if (m.impossible < 0 || m.impossible > ObservationEStep::kBlockSize)
    throw InputError("estep_result.impossible", "out of range");
  if (m.num_watched_steps != 0) {  // only from the block that holds the watched trajectory, all its steps
    if (shape.watch < 0 || m.block != shape.watch / ObservationEStep::kBlockSize ||
        m.num_watched_steps != shape.watch_steps) {
      throw InputError("estep_result.num_watched_steps", "is not the watched trajectory's length");
    }
    s.watched = eigen_rows<RowMatrix>(m.watched, pairs);
    const bool distributions = s.watched.allFinite() && (s.watched.array() >= 0.0).all() &&
                               ((s.watched.rowwise().sum().array() - 1.0).abs() <= 1e-6).all();
    if (!distributions) throw InputError("estep_result.watched", "each step's marginals must be a distribution");
    if (!std::isfinite(m.watched_log_likelihood))
      throw InputError("estep_result.watched_log_likelihood", "must be finite");
    s.watched_log_likelihood = m.watched_log_likelihood;
  }
  if (m.num_contexts != contexts || (contexts > 0 && m.num_sources != 1 + confounders)) {
    throw InputError("estep_result.num_contexts", "is not the request's number of contexts and sources");
  }
  if (m.num_counted < 0 || m.num_counted > contexts) throw InputError("estep_result.num_counted", "out of range");
  for (int k = 0; k < m.num_counted; ++k) {
    const int c = m.counted_context[static_cast<size_t>(k)];
    if (c < 0 || c >= contexts || (k > 0 && c <= m.counted_context[static_cast<size_t>(k) - 1])) {
      throw InputError("estep_result.counted_context", "must be increasing contexts of the request");
    }
    const std::vector<double>& row = m.source_counts[static_cast<size_t>(k)];
    if (!std::all_of(row.begin(), row.end(), [](double x) { return std::isfinite(x) && x >= 0.0; })) {
      throw InputError("estep_result.source_counts", "must be finite and >= 0");
    }
    s.source_counts.row(c) = Eigen::Map<const Eigen::RowVectorXd>(row.data(), static_cast<Eigen::Index>(row.size()));
  }
  s.log_likelihood = m.log_likelihood;
  s.impossible = m.impossible;
  return s;
}

bool same_statistics(const EStepStatistics& a, const EStepStatistics& b, double tolerance) {
  const auto close = [tolerance](const auto& x, const auto& y) {
    if (x.rows() != y.rows() || x.cols() != y.cols()) return false;
    if (tolerance == 0.0) return x == y;
    return ((x - y).array().abs() <= tolerance * (1.0 + y.array().abs())).all();
  };
  return close(a.counts, b.counts) && close(a.alpha_dot.subject, b.alpha_dot.subject) &&
         close(a.alpha_dot.end, b.alpha_dot.end) && close(a.alpha_dot.confounders, b.alpha_dot.confounders) &&
         close(a.source_counts, b.source_counts) &&
         (a.log_likelihood == b.log_likelihood ||
          std::abs(a.log_likelihood - b.log_likelihood) <= tolerance * (1.0 + std::abs(b.log_likelihood))) &&
         a.impossible == b.impossible && close(a.watched, b.watched) &&
         (a.watched_log_likelihood == b.watched_log_likelihood ||
          std::abs(a.watched_log_likelihood - b.watched_log_likelihood) <=
              tolerance * (1.0 + std::abs(b.watched_log_likelihood)));
}

}  // namespace hbirl::services
