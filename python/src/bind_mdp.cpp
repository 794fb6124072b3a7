// hbirl._hbirl's Mdp (bindings.hpp): built from dense arrays, rows or a scipy.sparse
// matrix, and what it computes (policies, values, ILE).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl::python {
namespace {

// An MDP's transitions or features as [i, j, k, value] rows (a problem file's lists), the
// index columns whole numbers >= 0.
struct Rows {
  std::vector<std::array<long long, 3>> index;
  std::vector<double> value;
};
Rows rows_of(const Array& rows, const std::string& name, const char* layout) {
  if (rows.ndim() != 2 || rows.shape(1) != 4)
    throw InputError(name, std::string("must be an (M, 4) array of ") + layout + " rows");
  const auto v = rows.unchecked<2>();
  Rows out;
  out.index.reserve(static_cast<size_t>(rows.shape(0)));
  for (py::ssize_t m = 0; m < rows.shape(0); ++m) {
    std::array<long long, 3> idx{};
    for (int j = 0; j < 3; ++j) {
      const double x = v(m, j);
      if (!(x >= 0.0 && x < 2147483647.0) || x != std::floor(x)) {
        throw InputError(name, "row " + std::to_string(m) + ": entry " + std::to_string(j) + " (" + std::to_string(x) +
                                   ") is not an index >= 0");
      }
      idx[static_cast<size_t>(j)] = static_cast<long long>(x);
    }
    out.index.push_back(idx);
    out.value.push_back(v(m, 3));
  }
  return out;
}

// A scipy.sparse (S*A, S) matrix as [s, a, s', p] rows; its shape fixes S and A (checked
// against num_states / num_actions when given).
Array sparse_transition_rows(const py::object& matrix, std::optional<int>& num_states,
                             std::optional<int>& num_actions) {
  const py::object coo = matrix.attr("tocoo")();
  const py::tuple shape = coo.attr("shape");
  if (shape.size() != 2) throw InputError("transitions", "a sparse matrix must be (S * A, S)");
  const auto rows = shape[0].cast<long long>(), cols = shape[1].cast<long long>();
  if (cols < 1 || rows < cols || rows % cols != 0 || rows > (1LL << 28))
    throw InputError("transitions", "a sparse matrix must be (S * A, S) with S * A <= 2^28");
  const long long sparse_actions = rows / cols;
  if (num_states && *num_states != cols)
    throw InputError("transitions",
                     "has " + std::to_string(cols) + " states, num_states " + std::to_string(*num_states));
  if (num_actions && *num_actions != sparse_actions)
    throw InputError("transitions",
                     "has " + std::to_string(sparse_actions) + " actions, num_actions " + std::to_string(*num_actions));
  num_states = static_cast<int>(cols);
  num_actions = static_cast<int>(sparse_actions);
  const IntArray row = coo.attr("row").cast<IntArray>(), col = coo.attr("col").cast<IntArray>();
  const Array data = coo.attr("data").cast<Array>();
  Array transitions(std::vector<py::ssize_t>{row.shape(0), 4});
  auto t = transitions.mutable_unchecked<2>();
  for (py::ssize_t m = 0; m < row.shape(0); ++m) {
    t(m, 0) = static_cast<double>(row.at(m) / sparse_actions);
    t(m, 1) = static_cast<double>(row.at(m) % sparse_actions);
    t(m, 2) = static_cast<double>(col.at(m));
    t(m, 3) = data.at(m);
  }
  return transitions;
}

// The MDP's transitions and features, each as a dense array or as rows.
struct MdpArrays {
  const Array& transitions;
  const Array& features;
  bool dense_t, dense_f;
  std::optional<Rows> t_rows, f_rows;
};

// S, A and K; -1 while not known.
struct MdpSizes {
  long long S = -1, A = -1, K = -1;
};

// The sizes the arguments state: num_states / num_actions / num_features, and the dense
// arrays' shapes, which must agree with them.
MdpSizes stated_sizes(const MdpArrays& in, std::optional<int> num_states, std::optional<int> num_actions,
                      std::optional<int> num_features) {
  for (const auto& [name, n] :
       {std::pair{"num_states", num_states}, {"num_actions", num_actions}, {"num_features", num_features}}) {
    if (n && *n < (std::string(name) == "num_features" ? 0 : 1)) throw InputError(name, "must be positive");
  }
  MdpSizes size{num_states.value_or(-1), num_actions.value_or(-1), num_features.value_or(-1)};
  const auto agree = [](long long& known, long long value, const char* name, const char* what) {
    if (known >= 0 && known != value)
      throw InputError(
          name, std::string("has ") + std::to_string(value) + " " + what + ", expected " + std::to_string(known));
    known = value;
  };
  if (in.dense_t) {
    if (in.transitions.shape(2) != in.transitions.shape(0))
      throw InputError("transitions", "must be an (S, A, S) array or (M, 4) rows");
    agree(size.S, in.transitions.shape(0), "transitions", "states");
    agree(size.A, in.transitions.shape(1), "transitions", "actions");
  }
  if (in.dense_f) {
    agree(size.S, in.features.shape(0), "features", "states");
    agree(size.A, in.features.shape(1), "features", "actions");
    agree(size.K, in.features.shape(2), "features", "features");
  }
  return size;
}

// The sizes not stated, from the largest index in the rows, and every size checked against
// the rows and bounded by what they can describe (every state terminal or with
// transitions, as in a problem file).
void complete_sizes(MdpSizes& size, const MdpArrays& in, size_t num_terminal) {
  long long max_s = -1, max_a = -1, max_k = -1;
  if (in.t_rows) {
    for (const auto& i : in.t_rows->index) max_s = std::max({max_s, i[0], i[2]}), max_a = std::max(max_a, i[1]);
  }
  if (in.f_rows) {
    for (const auto& i : in.f_rows->index)
      max_s = std::max(max_s, i[0]), max_a = std::max(max_a, i[1]), max_k = std::max(max_k, i[2]);
  }
  long long &S = size.S, &A = size.A, &K = size.K;
  if (S < 0) S = max_s + 1;
  if (A < 0) A = max_a + 1;
  if (K < 0) K = max_k + 1;
  if (S < 1 || A < 1) throw InputError("transitions", "give at least one state and one action");
  if (max_s >= S)
    throw InputError(in.t_rows ? "transitions" : "features",
                     "state " + std::to_string(max_s) + " is not in [0, " + std::to_string(S - 1) + "]");
  if (max_a >= A)
    throw InputError(in.t_rows ? "transitions" : "features",
                     "action " + std::to_string(max_a) + " is not in [0, " + std::to_string(A - 1) + "]");
  if (max_k >= K)
    throw InputError("features", "feature " + std::to_string(max_k) + " is not in [0, " + std::to_string(K - 1) + "]");
  if (in.t_rows && S > static_cast<long long>(in.t_rows->index.size() + num_terminal)) {
    throw InputError("num_states", std::to_string(S) + " states, but only " + std::to_string(in.t_rows->index.size()) +
                                       " transitions and " + std::to_string(num_terminal) +
                                       " terminal states (each state is terminal or has transitions)");
  }
  // With rows, a pair without any is an impossible action (as a dense row of zeros); but an
  // action no row uses at all cannot be asked for (a number alone must not claim gigabytes).
  if (in.t_rows && A > max_a + 1) {
    throw InputError("num_actions",
                     std::to_string(A) + ", but no transition uses an action above " + std::to_string(max_a));
  }
  if (S * A > (1LL << 28) || S * A * std::max(K, 1LL) > (1LL << 28))
    throw InputError("num_features", "num_states * num_actions * num_features is more than 2^28");
}

// One flag per state: terminal.
std::vector<char> terminal_flags(long long S, const std::vector<int>& terminal) {
  std::vector<char> is_terminal(static_cast<size_t>(S), 0);
  for (int s : terminal) {
    if (s < 0 || s >= S)
      throw InputError("terminal", "state " + std::to_string(s) + " is not in [0, " + std::to_string(S - 1) + "]");
    is_terminal[static_cast<size_t>(s)] = 1;
  }
  return is_terminal;
}

// One flag per (s, a): impossible.
std::vector<char> impossible_flags(long long S, long long A, const std::vector<std::pair<int, int>>& impossible) {
  std::vector<char> is_impossible(static_cast<size_t>(S * A), 0);
  for (const auto& [s, a] : impossible) {
    if (s < 0 || s >= S || a < 0 || a >= A) {
      throw InputError("impossible",
                       "(" + std::to_string(s) + ", " + std::to_string(a) + ") is not a state and action of the MDP");
    }
    is_impossible[static_cast<size_t>(s * A + a)] = 1;
  }
  return is_impossible;
}

// The transitions as entries, leaving out terminal states and impossible actions. No Python.
std::vector<TransitionEntry> transition_entries(const MdpArrays& in, const MdpSizes& size,
                                                const std::vector<char>& is_terminal,
                                                const std::vector<char>& is_impossible) {
  const long long S = size.S, A = size.A;
  const auto keep = [&](long long s, long long a) {
    return !is_terminal[static_cast<size_t>(s)] && !is_impossible[static_cast<size_t>(s * A + a)];
  };
  std::vector<TransitionEntry> entries;
  if (in.dense_t) {
    const auto p = in.transitions.unchecked<3>();
    for (int s = 0; s < S; ++s) {
      for (int a = 0; a < A; ++a) {
        if (!keep(s, a)) continue;
        for (int u = 0; u < S; ++u) {
          if (p(s, a, u) != 0.0) entries.push_back({s, a, u, p(s, a, u)});
        }
      }
    }
  } else {
    for (size_t m = 0; m < in.t_rows->index.size(); ++m) {
      const auto& i = in.t_rows->index[m];
      if (keep(i[0], i[1]))
        entries.push_back(
            {static_cast<int>(i[0]), static_cast<int>(i[1]), static_cast<int>(i[2]), in.t_rows->value[m]});
    }
  }
  return entries;
}

// The features as entries. No Python.
std::vector<FeatureEntry> feature_entries(const MdpArrays& in, const MdpSizes& size) {
  std::vector<FeatureEntry> phi;
  if (in.dense_f) {
    const auto f = in.features.unchecked<3>();
    for (int s = 0; s < size.S; ++s) {
      for (int a = 0; a < size.A; ++a) {
        for (int k = 0; k < size.K; ++k) {
          if (f(s, a, k) != 0.0) phi.push_back({s, a, k, f(s, a, k)});
        }
      }
    }
  } else {
    for (size_t m = 0; m < in.f_rows->index.size(); ++m) {
      const auto& i = in.f_rows->index[m];
      phi.push_back({static_cast<int>(i[0]), static_cast<int>(i[1]), static_cast<int>(i[2]), in.f_rows->value[m]});
    }
  }
  return phi;
}

// The start distribution given, else uniform over the non-terminal states, as in a problem file.
Eigen::VectorXd start_distribution(const std::optional<Eigen::VectorXd>& start, long long S,
                                   const std::vector<char>& is_terminal) {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(S);
  if (start) {
    d = *start;
  } else {
    for (int s = 0; s < S; ++s) d[s] = is_terminal[static_cast<size_t>(s)] ? 0.0 : 1.0;
    if (d.sum() == 0.0) throw InputError("terminal", "every state is terminal");
    d /= d.sum();
  }
  return d;
}

// An MDP from dense arrays or rows (docs/python.md "Python"). Sizes come from the dense arrays,
// else from num_states / num_actions / num_features, else from the largest index in the
// rows; they are bounded by what the rows can describe before anything is allocated
// (every state terminal or with transitions, as in a problem file). Checked as a problem
// file is (Mdp::validate), so bad input is a ValueError naming the argument.
Mdp make_python_mdp(const py::object& transitions_in, const Array& features,
                    const std::optional<Eigen::VectorXd>& start, const std::vector<int>& terminal, double discount,
                    const std::vector<std::pair<int, int>>& impossible, std::optional<int> num_states,
                    std::optional<int> num_actions, std::optional<int> num_features) {
  const Array transitions = py::hasattr(transitions_in, "tocoo")
                                ? sparse_transition_rows(transitions_in, num_states, num_actions)
                                : transitions_in.cast<Array>();
  MdpArrays in{transitions, features, transitions.ndim() == 3, features.ndim() == 3, std::nullopt, std::nullopt};
  if (!in.dense_t) in.t_rows = rows_of(transitions, "transitions", "[s, a, s', probability]");
  if (!in.dense_f) in.f_rows = rows_of(features, "features", "[s, a, k, value]");
  MdpSizes size = stated_sizes(in, num_states, num_actions, num_features);
  complete_sizes(size, in, terminal.size());
  if (start && start->size() != size.S)
    throw InputError("start", "must have one probability per state (" + std::to_string(size.S) + ")");
  const std::vector<char> is_terminal = terminal_flags(size.S, terminal);
  const std::vector<char> is_impossible = impossible_flags(size.S, size.A, impossible);
  py::gil_scoped_release released;  // the arrays are alive (the caller holds them); no Python below
  const std::vector<TransitionEntry> entries = transition_entries(in, size, is_terminal, is_impossible);
  const std::vector<FeatureEntry> phi = feature_entries(in, size);
  const Eigen::VectorXd d = start_distribution(start, size.S, is_terminal);
  try {
    Mdp mdp = make_mdp(static_cast<int>(size.S), static_cast<int>(size.A), static_cast<int>(size.K), entries, phi, d,
                       terminal, discount);
    mdp.validate();
    return mdp;
  } catch (const InputError& e) {  // named as the arguments are ("transitions", not a file's "mdp.transitions")
    const std::string field = e.field().rfind("mdp.", 0) == 0 ? e.field().substr(4) : e.field();
    throw InputError(field, e.message());
  }
}

std::vector<int> terminal_states(const Mdp& mdp) {
  std::vector<int> out;
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) out.push_back(s);
  }
  return out;
}

Eigen::MatrixXd transition_rows(const Mdp& mdp) {
  const Eigen::SparseMatrix<double, Eigen::RowMajor> t = mdp.transitions;
  Eigen::MatrixXd out(t.nonZeros(), 4);
  Eigen::Index k = 0;
  for (int r = 0; r < t.outerSize(); ++r) {
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(t, r); it; ++it, ++k) {
      out.row(k) << r / mdp.num_actions, r % mdp.num_actions, static_cast<double>(it.col()), it.value();
    }
  }
  return out;
}

py::tuple optimal_policy_of(const Mdp& mdp, const Array& reward) {
  if (reward.ndim() != 2 || reward.shape(0) != mdp.num_states || reward.shape(1) != mdp.num_actions) {
    throw InputError("reward", "must be an (S, A) array");
  }
  const auto v = reward.unchecked<2>();
  Eigen::VectorXd r(mdp.num_pairs());
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) r[mdp.pair(s, a)] = v(s, a);
  }
  if (!r.allFinite()) throw InputError("reward", "must be finite");
  OptimalPolicy best;
  {
    py::gil_scoped_release released;
    best = value_iteration(mdp, r);
  }
  return py::make_tuple(best.actions, best.value);
}

}  // namespace

void bind_mdp(py::module_& m) {
  py::class_<Mdp>(
      m, "Mdp", "A finite MDP: states, actions, transitions, features, start distribution, terminal states, discount.")
      .def(py::init(&make_python_mdp), py::arg("transitions"), py::arg("features"), py::arg("start") = py::none(),
           py::arg("terminal") = std::vector<int>{}, py::arg("discount") = 0.95,
           py::arg("impossible") = std::vector<std::pair<int, int>>{}, py::arg("num_states") = py::none(),
           py::arg("num_actions") = py::none(), py::arg("num_features") = py::none())
      .def_property_readonly("num_states", [](const Mdp& mdp) { return mdp.num_states; })
      .def_property_readonly("num_actions", [](const Mdp& mdp) { return mdp.num_actions; })
      .def_property_readonly("num_features", &Mdp::num_features)
      .def_property_readonly("discount", [](const Mdp& mdp) { return mdp.discount; })
      .def_property_readonly("start", [](const Mdp& mdp) { return mdp.start; })
      .def_property_readonly("terminal", &terminal_states, "The terminal states.")
      .def("transition_rows", &transition_rows, "The transitions as (M, 4) rows [s, a, s', probability].")
      .def(
          "reward",
          [](const Mdp& mdp, const Eigen::VectorXd& theta) {
            return per_state_action(mdp, mdp.reward(theta_of(mdp, theta, "theta")));
          },
          py::arg("theta"), "R(s, a) = theta . phi(s, a) as an (S, A) array.")
      .def(
          "soft_policy",
          [](const Mdp& mdp, const Eigen::VectorXd& theta) {
            const Eigen::VectorXd r = mdp.reward(theta_of(mdp, theta, "theta"));
            Eigen::VectorXd policy;
            {
              py::gil_scoped_release released;
              policy = soft_value_iteration(mdp, r).policy;
            }
            return per_state_action(mdp, policy);
          },
          py::arg("theta"),
          "The MaxCausalEnt (soft) policy pi(a | s) for reward weights theta, an (S, A) array (0 on terminal states).")
      .def(
          "soft_values",
          [](const Mdp& mdp, const Eigen::VectorXd& theta) {
            const Eigen::VectorXd r = mdp.reward(theta_of(mdp, theta, "theta"));
            py::gil_scoped_release released;
            return Eigen::VectorXd(soft_value_iteration(mdp, r).value);
          },
          py::arg("theta"), "The soft values V(s) for reward weights theta, an (S,) array (0 at terminal states).")
      .def("optimal_policy", &optimal_policy_of, py::arg("reward"),
           "The optimal policy for an (S, A) reward: (actions, values), a greedy action per state (-1 at terminal\n"
           "states, the lowest index among ties) and V*(s).");

  m.def(
      "ile",
      [](const Mdp& mdp, const Eigen::VectorXd& true_theta, const Eigen::VectorXd& learned_theta) {
        const Eigen::VectorXd t = theta_of(mdp, true_theta, "true_theta"),
                              l = theta_of(mdp, learned_theta, "learned_theta");
        py::gil_scoped_release released;
        return inverse_learning_error(mdp, t, l).ile;
      },
      py::arg("mdp"), py::arg("true_theta"), py::arg("learned_theta"),
      "Inverse learning error: the L1 distance between the values of the optimal policies of the true and the\n"
      "learned reward, both under the true reward (paper §Experiments).");
}

}  // namespace hbirl::python
