// numpy <-> hbirl conversions (arrays.hpp).
#include "arrays.hpp"

#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>

#include "learner/input_error.hpp"

namespace hbirl::python {

namespace {

// A data set's steps, summed over trajectories: bounded before the per-step arrays are
// allocated (a few numbers can claim billions of occluded steps).
constexpr long long kMaxSteps = 1LL << 26;

std::string at(int trajectory, long long step) {
  return "observations[" + std::to_string(trajectory) + "][" + std::to_string(step) + "]";
}

// The trajectory lengths, checked, and their total.
long long checked_lengths(const IntArray& lengths) {
  if (lengths.ndim() != 1 || lengths.shape(0) < 1)
    throw InputError("observations.lengths", "must be a 1-D array of at least one trajectory's step count");
  const auto l = lengths.unchecked<1>();
  long long total = 0;
  for (py::ssize_t i = 0; i < lengths.shape(0); ++i) {
    if (l(i) < 1)
      throw InputError("observations.lengths",
                       "trajectory " + std::to_string(i) + " has " + std::to_string(l(i)) + " steps; at least 1");
    if (l(i) > kMaxSteps - total)
      throw InputError("observations.lengths",
                       "more than " + std::to_string(kMaxSteps) + " steps in all");  // before adding: no overflow
    total += l(i);
  }
  return total;
}

// The flat form's arrays have one entry (eta: one row of 1 + |E|) per observation.
void check_flat_shapes(const FlatObservations& flat, const ObservationPrior& prior) {
  const int sources = 1 + prior.num_confounders;
  if (flat.symbols.ndim() != 1)
    throw InputError("observations.symbols", "must be a 1-D array, one symbol per observation");
  const py::ssize_t n = flat.symbols.shape(0);
  if (flat.eta.ndim() != 2 || flat.eta.shape(0) != n || flat.eta.shape(1) != sources) {
    throw InputError("observations.eta", "must be an (N, " + std::to_string(sources) +
                                             ") array: one row per observation, the subject and " +
                                             std::to_string(prior.num_confounders) + " confounders (the prior's)");
  }
  if (flat.step_index.ndim() != 1 || flat.step_index.shape(0) != n)
    throw InputError("observations.step_index", "must be a 1-D array, one step per observation");
  if (flat.contexts && (flat.contexts->ndim() != 1 || flat.contexts->shape(0) != n)) {
    throw InputError("observations.contexts", "must be a 1-D array, one context per observation");
  }
}

// The forward-backward pass (and a posterior's marginals) hold T x (S * A) doubles per
// trajectory: bounded here, before anything is computed.
void check_pass_sizes(const IntArray& lengths_array, const Mdp& mdp) {
  const auto lengths = lengths_array.unchecked<1>();
  for (py::ssize_t i = 0; i < lengths_array.shape(0); ++i) {
    if (lengths(i) * static_cast<long long>(mdp.num_pairs()) > (1LL << 28)) {
      throw InputError("observations.lengths", "trajectory " + std::to_string(i) + " has " +
                                                   std::to_string(lengths(i)) + " steps: with the MDP's " +
                                                   std::to_string(mdp.num_pairs()) +
                                                   " state-action pairs more than the 2^28 cells a pass may hold");
    }
  }
}

// Whether the MDP has terminal states: as in a problem file, by default a trajectory ran
// until it entered one when it has them. ends_in_terminal, when given, is checked against it.
bool check_ends_in_terminal(const FlatObservations& flat, int trajectories, const Mdp& mdp) {
  if (flat.ends_in_terminal && flat.ends_in_terminal->size() != static_cast<size_t>(trajectories)) {
    throw InputError("observations.ends_in_terminal", "must have one entry per trajectory");
  }
  const bool has_terminal = std::find(mdp.terminal.begin(), mdp.terminal.end(), 1) != mdp.terminal.end();
  if (flat.ends_in_terminal && !has_terminal) {
    for (size_t i = 0; i < flat.ends_in_terminal->size(); ++i) {
      if ((*flat.ends_in_terminal)[i])
        throw InputError("observations.ends_in_terminal",
                         "trajectory " + std::to_string(i) + ": true, but the MDP has no terminal states");
    }
  }
  return has_terminal;
}

// The flat form's per-observation arrays, read without checks (their shapes are checked).
struct FlatView {
  py::detail::unchecked_reference<long long, 1> symbols;
  py::detail::unchecked_reference<double, 2> eta;
  py::detail::unchecked_reference<long long, 1> steps;
  py::detail::unchecked_reference<long long, 1> contexts;
  bool has_contexts;
};

// Observation m, the trajectory's observation m - begin, added to t: its symbol, its eta
// (normalised) and its context, checked; `where` names it.
void add_observation(ObservedTrajectory& t, const FlatView& in, py::ssize_t m, py::ssize_t begin,
                     const std::string& where, const ObservationPrior& prior) {
  const int sources = 1 + prior.num_confounders;
  if (in.symbols(m) < 0 || in.symbols(m) >= prior.num_symbols) {
    throw InputError(where, "symbol " + std::to_string(in.symbols(m)) + " is not in [0, " +
                                std::to_string(prior.num_symbols - 1) + "]");
  }
  t.symbols.push_back(static_cast<int>(in.symbols(m)));
  const Eigen::Index row = m - begin;
  for (int j = 0; j < sources; ++j) {
    const double v = in.eta(m, j);
    if (!(v >= 0.0 && v <= 1.0))
      throw InputError(where, "eta[" + std::to_string(j) + "] is " + std::to_string(v) + ", not in [0, 1]");
    t.eta(row, j) = v;
  }
  const std::string wrong = normalise_eta(t.eta.row(row).data(), sources);
  if (!wrong.empty()) throw InputError(where, "eta " + wrong);
  if (in.has_contexts) {
    // -1: none (a trajectory gives contexts to all its observations or none, as in a problem file).
    const long long c = in.contexts(m);
    if (c < -1 || c >= kMaxContexts)
      throw InputError(where, "context " + std::to_string(c) + " is not in [0, " + std::to_string(kMaxContexts - 1) +
                                  "] (or -1: none)");
    if ((c == -1) != (m == begin ? c == -1 : t.contexts.empty())) {
      throw InputError(where, "some observations of the trajectory have a context and others not (-1)");
    }
    if (c >= 0) t.contexts.push_back(static_cast<int>(c));
  }
}

// What was seen of each trajectory's end (end_state, end_symbols), checked against the MDP's
// terminal states and the prior's end sensor and added to `out` (ends_in_terminal set).
void add_ends(const FlatObservations& flat, const ObservationPrior& prior, const Mdp& mdp,
              std::vector<ObservedTrajectory>& out) {
  const auto trajectories = static_cast<py::ssize_t>(out.size());
  const auto needs_terminal_end = [&](const char* field, py::ssize_t i) {
    if (!out[static_cast<size_t>(i)].ends_in_terminal)
      throw InputError(field, "trajectory " + std::to_string(i) +
                                  ": given, but the trajectory does not end in a terminal state (ends_in_terminal)");
  };
  if (flat.end_state) {
    if (flat.end_state->ndim() != 1 || flat.end_state->shape(0) != trajectories)
      throw InputError("observations.end_state", "must be a 1-D array, one state (or -1) per trajectory");
    const auto v = flat.end_state->unchecked<1>();
    for (py::ssize_t i = 0; i < trajectories; ++i) {
      if (v(i) == -1) continue;
      if (v(i) < 0 || v(i) >= mdp.num_states || !mdp.is_terminal(static_cast<int>(v(i))))
        throw InputError("observations.end_state", "trajectory " + std::to_string(i) + ": " + std::to_string(v(i)) +
                                                       " is not a terminal state of the MDP (or -1: not seen)");
      needs_terminal_end("observations.end_state", i);
      out[static_cast<size_t>(i)].end_state = static_cast<int>(v(i));
    }
  }
  if (!flat.end_symbols) return;
  if (static_cast<py::ssize_t>(flat.end_symbols->size()) != trajectories)
    throw InputError("observations.end_symbols", "must have one entry (reports, maybe none) per trajectory");
  const int K = prior.num_end_symbols();
  for (py::ssize_t i = 0; i < trajectories; ++i) {
    const IntArray& reports = (*flat.end_symbols)[static_cast<size_t>(i)];
    const std::string where = "observations.end_symbols[" + std::to_string(i) + "]";
    if (reports.ndim() != 1) throw InputError(where, "must be a 1-D array of the end sensor's symbols");
    if (reports.shape(0) == 0) continue;
    if (K == 0) throw InputError(where, "reports given, but the prior has no end sensor (num_end_symbols)");
    if (reports.shape(0) > kMaxEndReports)
      throw InputError(where, "has " + std::to_string(reports.shape(0)) + " reports, more than the " +
                                  std::to_string(kMaxEndReports) + " one ending may have");
    needs_terminal_end(where.c_str(), i);
    const auto r = reports.unchecked<1>();
    std::vector<int>& symbols = out[static_cast<size_t>(i)].end_symbols;
    for (py::ssize_t k = 0; k < reports.shape(0); ++k) {
      if (r(k) < 0 || r(k) >= K)
        throw InputError(where, "symbol " + std::to_string(r(k)) + " is not in [0, " + std::to_string(K - 1) + "]");
      symbols.push_back(static_cast<int>(r(k)));
    }
  }
}

}  // namespace

std::vector<ObservedTrajectory> observed_trajectories(const FlatObservations& flat, const ObservationPrior& prior,
                                                      const Mdp& mdp) {
  const int sources = 1 + prior.num_confounders;
  check_flat_shapes(flat, prior);
  const py::ssize_t n = flat.symbols.shape(0);
  const long long total_steps = checked_lengths(flat.lengths);
  const auto lengths = flat.lengths.unchecked<1>();
  check_pass_sizes(flat.lengths, mdp);
  const auto trajectories = static_cast<int>(flat.lengths.shape(0));
  const bool has_terminal = check_ends_in_terminal(flat, trajectories, mdp);
  const IntArray no_contexts(0);
  const FlatView in{flat.symbols.unchecked<1>(), flat.eta.unchecked<2>(), flat.step_index.unchecked<1>(),
                    (flat.contexts ? *flat.contexts : no_contexts).unchecked<1>(), flat.contexts.has_value()};
  const auto& steps = in.steps;
  std::vector<ObservedTrajectory> out(static_cast<size_t>(trajectories));
  py::ssize_t k = 0;  // the next observation
  long long first_step = 0;
  for (int i = 0; i < trajectories; ++i) {
    ObservedTrajectory& t = out[static_cast<size_t>(i)];
    t.step_begin.assign(1, 0);
    t.ends_in_terminal =
        flat.ends_in_terminal ? static_cast<bool>((*flat.ends_in_terminal)[static_cast<size_t>(i)]) : has_terminal;
    const long long end_step = first_step + lengths(i);
    py::ssize_t begin = k;
    while (k < n && steps(k) < end_step) ++k;
    t.symbols.reserve(static_cast<size_t>(k - begin));
    t.eta.resize(k - begin, sources);
    if (flat.contexts) t.contexts.reserve(static_cast<size_t>(k - begin));
    long long step = first_step;
    for (py::ssize_t m = begin; m < k; ++m) {
      if (steps(m) < step) {
        throw InputError("observations.step_index",
                         "entry " + std::to_string(m) + " (" + std::to_string(steps(m)) +
                             ") is smaller than the one before it: observations go in step order");
      }
      for (; step < steps(m); ++step) t.step_begin.push_back(static_cast<int>(m - begin));
      add_observation(t, in, m, begin, at(i, steps(m) - first_step), prior);
    }
    for (; step < end_step; ++step) t.step_begin.push_back(static_cast<int>(k - begin));
    first_step = end_step;
  }
  add_ends(flat, prior, mdp, out);
  if (k < n) {
    throw InputError("observations.step_index", "entry " + std::to_string(k) + " (" + std::to_string(steps(k)) +
                                                    ") is not a step of the " + std::to_string(total_steps) +
                                                    " the lengths give (or is out of order)");
  }
  return out;
}

py::tuple flat_observations(const std::vector<ObservedTrajectory>& trajectories) {
  size_t n = 0;
  int sources = 1;
  bool any_context = false;
  for (const auto& t : trajectories) {
    n += static_cast<size_t>(t.num_observations());
    if (t.num_observations() > 0) sources = static_cast<int>(t.eta.cols());
    any_context = any_context || !t.contexts.empty();
  }
  const auto N = static_cast<py::ssize_t>(n);
  IntArray symbols(N), step_index(N), lengths(static_cast<py::ssize_t>(trajectories.size()));
  Array eta(std::vector<py::ssize_t>{N, sources});
  IntArray contexts(any_context ? N : 0);
  auto sy = symbols.mutable_unchecked<1>();
  auto st = step_index.mutable_unchecked<1>();
  auto le = lengths.mutable_unchecked<1>();
  auto et = eta.mutable_unchecked<2>();
  auto co = contexts.mutable_unchecked<1>();
  std::vector<bool> terminal;
  bool any_end_state = false, any_end_symbols = false;
  for (const auto& t : trajectories) {
    any_end_state = any_end_state || t.end_state >= 0;
    any_end_symbols = any_end_symbols || !t.end_symbols.empty();
  }
  IntArray end_state(any_end_state ? static_cast<py::ssize_t>(trajectories.size()) : 0);
  auto es = end_state.mutable_unchecked<1>();
  py::list end_symbols;
  py::ssize_t k = 0;
  long long first_step = 0;
  for (size_t i = 0; i < trajectories.size(); ++i) {
    const ObservedTrajectory& t = trajectories[i];
    le(static_cast<py::ssize_t>(i)) = t.length();
    terminal.push_back(t.ends_in_terminal);
    if (any_end_state) es(static_cast<py::ssize_t>(i)) = t.end_state;
    if (any_end_symbols) {
      IntArray reports(static_cast<py::ssize_t>(t.end_symbols.size()));
      auto r = reports.mutable_unchecked<1>();
      for (size_t j = 0; j < t.end_symbols.size(); ++j) r(static_cast<py::ssize_t>(j)) = t.end_symbols[j];
      end_symbols.append(reports);
    }
    for (int s = 0; s < t.length(); ++s) {
      for (int m = t.step_begin[static_cast<size_t>(s)]; m < t.step_begin[static_cast<size_t>(s) + 1]; ++m, ++k) {
        sy(k) = t.symbols[static_cast<size_t>(m)];
        st(k) = first_step + s;
        for (int j = 0; j < sources; ++j) et(k, j) = t.eta(m, j);
        if (any_context) co(k) = t.context(m);
      }
    }
    first_step += t.length();
  }
  return py::make_tuple(symbols, eta, step_index, lengths, any_context ? py::object(contexts) : py::object(py::none()),
                        terminal, any_end_symbols ? py::object(end_symbols) : py::object(py::none()),
                        any_end_state ? py::object(end_state) : py::object(py::none()));
}

FlatObservations flat_of(const py::tuple& t) {
  if (t.size() != 8) throw InputError("observations", "internal: expected 8 parts");
  FlatObservations f{t[0].cast<IntArray>(), t[1].cast<Array>(), t[2].cast<IntArray>(), t[3].cast<IntArray>(),
                     std::nullopt,          std::nullopt,       std::nullopt,          std::nullopt};
  if (!t[4].is_none()) f.contexts = t[4].cast<IntArray>();
  if (!t[5].is_none()) f.ends_in_terminal = t[5].cast<std::vector<bool>>();
  if (!t[6].is_none()) f.end_symbols = t[6].cast<std::vector<IntArray>>();
  if (!t[7].is_none()) f.end_state = t[7].cast<IntArray>();
  return f;
}

py::array_t<double> per_state_action(const Mdp& mdp, const Eigen::VectorXd& pairs) {
  py::array_t<double> out(std::vector<py::ssize_t>{mdp.num_states, mdp.num_actions});
  auto m = out.mutable_unchecked<2>();
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) m(s, a) = pairs[mdp.pair(s, a)];
  }
  return out;
}

py::array_t<double> per_state_action_symbol(const Mdp& mdp, const Eigen::MatrixXd& rows) {
  const auto W = static_cast<py::ssize_t>(rows.cols());
  py::array_t<double> out(std::vector<py::ssize_t>{mdp.num_states, mdp.num_actions, W});
  auto m = out.mutable_unchecked<3>();
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      for (py::ssize_t w = 0; w < W; ++w) m(s, a, w) = rows(mdp.pair(s, a), w);
    }
  }
  return out;
}

Eigen::MatrixXd pair_rows(const Mdp& mdp, const Array& sa_w, const std::string& name) {
  if (sa_w.ndim() != 3 || sa_w.shape(0) != mdp.num_states || sa_w.shape(1) != mdp.num_actions || sa_w.shape(2) < 1) {
    throw InputError(name, "must be an (S, A, W) array with the MDP's S = " + std::to_string(mdp.num_states) +
                               " and A = " + std::to_string(mdp.num_actions));
  }
  const auto v = sa_w.unchecked<3>();
  Eigen::MatrixXd out(mdp.num_pairs(), sa_w.shape(2));
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      for (py::ssize_t w = 0; w < sa_w.shape(2); ++w) out(mdp.pair(s, a), w) = v(s, a, w);
    }
  }
  return out;
}

Eigen::VectorXd theta_of(const Mdp& mdp, const Eigen::VectorXd& theta, const std::string& name) {
  if (theta.size() != mdp.num_features()) {
    throw InputError(name, "has " + std::to_string(theta.size()) + " weights, the MDP " +
                               std::to_string(mdp.num_features()) + " features");
  }
  if (!theta.allFinite()) throw InputError(name, "must be finite");
  return theta;
}

std::vector<Trajectory> trajectories_of(const Mdp& mdp, const std::vector<IntArray>& arrays, const std::string& name) {
  if (arrays.empty()) throw InputError(name, "none given");
  std::vector<Trajectory> out;
  for (size_t i = 0; i < arrays.size(); ++i) {
    const IntArray& a = arrays[i];
    const std::string item = name + "[" + std::to_string(i) + "]";
    if (a.ndim() != 2 || a.shape(1) != 2 || a.shape(0) < 1)
      throw InputError(item, "must be a (T, 2) array of (state, action), T >= 1");
    const auto v = a.unchecked<2>();
    Trajectory t;
    for (py::ssize_t k = 0; k < a.shape(0); ++k) {
      const long long s = v(k, 0), act = v(k, 1);
      if (s < 0 || s >= mdp.num_states || act < 0 || act >= mdp.num_actions) {
        throw InputError(item, "step " + std::to_string(k) + ": (" + std::to_string(s) + ", " + std::to_string(act) +
                                   ") is not a state and action of the MDP");
      }
      t.push_back({static_cast<int>(s), static_cast<int>(act)});
    }
    out.push_back(std::move(t));
  }
  return out;
}

py::list trajectories_to_arrays(const std::vector<Trajectory>& trajectories) {
  py::list out;
  for (const Trajectory& t : trajectories) {
    IntArray a(std::vector<py::ssize_t>{static_cast<py::ssize_t>(t.size()), 2});
    auto m = a.mutable_unchecked<2>();
    for (size_t k = 0; k < t.size(); ++k) {
      m(static_cast<py::ssize_t>(k), 0) = t[k].state;
      m(static_cast<py::ssize_t>(k), 1) = t[k].action;
    }
    out.append(a);
  }
  return out;
}

}  // namespace hbirl::python
