// hbirl._hbirl: the C++ core for Python (pybind11), numpy arrays in and out. The package
// around it (python/hbirl/__init__.py) adds the scikit-learn-style estimators and the
// input forms numpy cannot check alone; shapes and conventions are documented there and
// in README.md "Python". Every long call releases the GIL.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "arrays.hpp"
#include "app/learn.hpp"
#include "hierarchical.hpp"
#include "recording.hpp"
#include "learner/controlled_prior.hpp"
#include "learner/estep.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/maxcausalent.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/value_iteration.hpp"
#include "problem/domain_file.hpp"
#include "problem/json_format.hpp"
#include "problem/problem_file.hpp"
#include "problem/problem_observations.hpp"
#include "sim_driver/gridworld/problem_file.hpp"
#include "sim_driver/onion/onion.hpp"

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

// An MDP from dense arrays or rows (README.md "Python"). Sizes come from the dense arrays,
// else from num_states / num_actions / num_features, else from the largest index in the
// rows; they are bounded by what the rows can describe before anything is allocated
// (every state terminal or with transitions, as in a problem file). Checked as a problem
// file is (Mdp::validate), so bad input is a ValueError naming the argument.
Mdp make_python_mdp(const py::object& transitions_in, const Array& features,
                    const std::optional<Eigen::VectorXd>& start, const std::vector<int>& terminal, double discount,
                    const std::vector<std::pair<int, int>>& impossible, std::optional<int> num_states,
                    std::optional<int> num_actions, std::optional<int> num_features) {
  // A scipy.sparse (S*A, S) matrix becomes [s, a, s', p] rows (its sizes fix S and A).
  Array transitions;
  if (py::hasattr(transitions_in, "tocoo")) {
    const py::object coo = transitions_in.attr("tocoo")();
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
      throw InputError("transitions", "has " + std::to_string(sparse_actions) + " actions, num_actions " +
                                          std::to_string(*num_actions));
    num_states = static_cast<int>(cols);
    num_actions = static_cast<int>(sparse_actions);
    const IntArray row = coo.attr("row").cast<IntArray>(), col = coo.attr("col").cast<IntArray>();
    const Array data = coo.attr("data").cast<Array>();
    transitions = Array(std::vector<py::ssize_t>{row.shape(0), 4});
    auto t = transitions.mutable_unchecked<2>();
    for (py::ssize_t m = 0; m < row.shape(0); ++m) {
      t(m, 0) = static_cast<double>(row.at(m) / sparse_actions);
      t(m, 1) = static_cast<double>(row.at(m) % sparse_actions);
      t(m, 2) = static_cast<double>(col.at(m));
      t(m, 3) = data.at(m);
    }
  } else {
    transitions = transitions_in.cast<Array>();
  }
  const bool dense_t = transitions.ndim() == 3, dense_f = features.ndim() == 3;
  std::optional<Rows> t_rows, f_rows;
  if (!dense_t) t_rows = rows_of(transitions, "transitions", "[s, a, s', probability]");
  if (!dense_f) f_rows = rows_of(features, "features", "[s, a, k, value]");
  for (const auto& [name, n] :
       {std::pair{"num_states", num_states}, {"num_actions", num_actions}, {"num_features", num_features}}) {
    if (n && *n < (std::string(name) == "num_features" ? 0 : 1)) throw InputError(name, "must be positive");
  }
  long long S = num_states.value_or(-1), A = num_actions.value_or(-1), K = num_features.value_or(-1);
  const auto agree = [](long long& size, long long value, const char* name, const char* what) {
    if (size >= 0 && size != value)
      throw InputError(name,
                       std::string("has ") + std::to_string(value) + " " + what + ", expected " + std::to_string(size));
    size = value;
  };
  if (dense_t) {
    if (transitions.shape(2) != transitions.shape(0))
      throw InputError("transitions", "must be an (S, A, S) array or (M, 4) rows");
    agree(S, transitions.shape(0), "transitions", "states");
    agree(A, transitions.shape(1), "transitions", "actions");
  }
  if (dense_f) {
    agree(S, features.shape(0), "features", "states");
    agree(A, features.shape(1), "features", "actions");
    agree(K, features.shape(2), "features", "features");
  }
  long long max_s = -1, max_a = -1, max_k = -1;
  if (t_rows) {
    for (const auto& i : t_rows->index) max_s = std::max({max_s, i[0], i[2]}), max_a = std::max(max_a, i[1]);
  }
  if (f_rows) {
    for (const auto& i : f_rows->index)
      max_s = std::max(max_s, i[0]), max_a = std::max(max_a, i[1]), max_k = std::max(max_k, i[2]);
  }
  if (S < 0) S = max_s + 1;
  if (A < 0) A = max_a + 1;
  if (K < 0) K = max_k + 1;
  if (S < 1 || A < 1) throw InputError("transitions", "give at least one state and one action");
  if (max_s >= S)
    throw InputError(t_rows ? "transitions" : "features",
                     "state " + std::to_string(max_s) + " is not in [0, " + std::to_string(S - 1) + "]");
  if (max_a >= A)
    throw InputError(t_rows ? "transitions" : "features",
                     "action " + std::to_string(max_a) + " is not in [0, " + std::to_string(A - 1) + "]");
  if (max_k >= K)
    throw InputError("features", "feature " + std::to_string(max_k) + " is not in [0, " + std::to_string(K - 1) + "]");
  if (t_rows && S > static_cast<long long>(t_rows->index.size() + terminal.size())) {
    throw InputError("num_states", std::to_string(S) + " states, but only " + std::to_string(t_rows->index.size()) +
                                       " transitions and " + std::to_string(terminal.size()) +
                                       " terminal states (each state is terminal or has transitions)");
  }
  // With rows, a pair without any is an impossible action (as a dense row of zeros); but an
  // action no row uses at all cannot be asked for (a number alone must not claim gigabytes).
  if (t_rows && A > max_a + 1) {
    throw InputError("num_actions",
                     std::to_string(A) + ", but no transition uses an action above " + std::to_string(max_a));
  }
  if (S * A > (1LL << 28) || S * A * std::max(K, 1LL) > (1LL << 28))
    throw InputError("num_features", "num_states * num_actions * num_features is more than 2^28");
  if (start && start->size() != S)
    throw InputError("start", "must have one probability per state (" + std::to_string(S) + ")");
  std::vector<char> is_terminal(static_cast<size_t>(S), 0);
  for (int s : terminal) {
    if (s < 0 || s >= S)
      throw InputError("terminal", "state " + std::to_string(s) + " is not in [0, " + std::to_string(S - 1) + "]");
    is_terminal[static_cast<size_t>(s)] = 1;
  }
  std::vector<char> is_impossible(static_cast<size_t>(S * A), 0);
  for (const auto& [s, a] : impossible) {
    if (s < 0 || s >= S || a < 0 || a >= A) {
      throw InputError("impossible",
                       "(" + std::to_string(s) + ", " + std::to_string(a) + ") is not a state and action of the MDP");
    }
    is_impossible[static_cast<size_t>(s * A + a)] = 1;
  }
  py::gil_scoped_release released;  // the arrays are alive (the caller holds them); no Python below
  const auto keep = [&](long long s, long long a) {
    return !is_terminal[static_cast<size_t>(s)] && !is_impossible[static_cast<size_t>(s * A + a)];
  };
  std::vector<TransitionEntry> entries;
  if (dense_t) {
    const auto p = transitions.unchecked<3>();
    for (int s = 0; s < S; ++s) {
      for (int a = 0; a < A; ++a) {
        if (!keep(s, a)) continue;
        for (int u = 0; u < S; ++u) {
          if (p(s, a, u) != 0.0) entries.push_back({s, a, u, p(s, a, u)});
        }
      }
    }
  } else {
    for (size_t m = 0; m < t_rows->index.size(); ++m) {
      const auto& i = t_rows->index[m];
      if (keep(i[0], i[1]))
        entries.push_back({static_cast<int>(i[0]), static_cast<int>(i[1]), static_cast<int>(i[2]), t_rows->value[m]});
    }
  }
  std::vector<FeatureEntry> phi;
  if (dense_f) {
    const auto f = features.unchecked<3>();
    for (int s = 0; s < S; ++s) {
      for (int a = 0; a < A; ++a) {
        for (int k = 0; k < K; ++k) {
          if (f(s, a, k) != 0.0) phi.push_back({s, a, k, f(s, a, k)});
        }
      }
    }
  } else {
    for (size_t m = 0; m < f_rows->index.size(); ++m) {
      const auto& i = f_rows->index[m];
      phi.push_back({static_cast<int>(i[0]), static_cast<int>(i[1]), static_cast<int>(i[2]), f_rows->value[m]});
    }
  }
  Eigen::VectorXd d = Eigen::VectorXd::Zero(S);
  if (start) {
    d = *start;
  } else {  // uniform over the non-terminal states, as in a problem file
    for (int s = 0; s < S; ++s) d[s] = is_terminal[static_cast<size_t>(s)] ? 0.0 : 1.0;
    if (d.sum() == 0.0) throw InputError("terminal", "every state is terminal");
    d /= d.sum();
  }
  try {
    Mdp mdp =
        make_mdp(static_cast<int>(S), static_cast<int>(A), static_cast<int>(K), entries, phi, d, terminal, discount);
    mdp.validate();
    return mdp;
  } catch (const InputError& e) {  // named as the arguments are ("transitions", not a file's "mdp.transitions")
    const std::string field = e.field().rfind("mdp.", 0) == 0 ? e.field().substr(4) : e.field();
    throw InputError(field, e.message());
  }
}

// An observation prior from arrays (README.md "Python"): the subject's alpha as a number
// (every (s, a) and symbol) or an (S, A, W) array, the confounders' as a number or an
// (E, W) array; checked as a problem file's observation_model is.
// A number (Python's or numpy's scalar, or a 0-d array), else nothing.
std::optional<double> number_of(const py::object& value, const std::string& name) {
  if (py::isinstance<py::bool_>(value) || py::isinstance<py::str>(value) || value.is_none()) {
    throw InputError(name, "must be a number or an array");
  }
  if (py::module_::import("numpy").attr("ndim")(value).cast<int>() != 0) return std::nullopt;
  try {
    return py::float_(value).cast<double>();
  } catch (const py::error_already_set&) {
    throw InputError(name, "must be a number or an array");
  }
}

Array array_of(const py::object& value, const std::string& name) {
  try {
    return value.cast<Array>();
  } catch (const py::cast_error&) {
    throw InputError(name, "must be a number or an array of numbers");
  }
}

ObservationPrior make_prior(const Mdp& mdp, int num_symbols, int num_confounders, const py::object& subject_alpha,
                            const py::object& confounder_alpha, std::optional<double> subject_alpha_default,
                            const std::string& update, double c, const py::object& prior_strength,
                            std::optional<bool> learn, std::optional<bool> learn_eta, double eta_strength,
                            double unlisted_eta) {
  if (num_symbols < 1) throw InputError("num_symbols", "must be at least 1");
  if (num_confounders < 0) throw InputError("num_confounders", "must be >= 0");
  if ((static_cast<long long>(mdp.num_pairs()) + num_confounders) * num_symbols > (1LL << 28)) {
    throw InputError(
        num_confounders > mdp.num_pairs() ? "num_confounders" : "num_symbols",
        "(num_states * num_actions + num_confounders) * num_symbols is more than an observation model may take (2^28)");
  }
  ObservationPrior prior;
  prior.num_symbols = num_symbols;
  prior.num_confounders = num_confounders;
  // subject_alpha_default is the base of the posterior update's power prior (a problem
  // file's subject_alpha_default, observations.hpp): counts above it are what the prior
  // strength weighs. A number given for subject_alpha is its own base, as in a file that
  // gives only subject_alpha_default.
  if (const std::optional<double> a = number_of(subject_alpha, "subject_alpha")) {
    if (!(*a > 0.0) || !std::isfinite(*a)) throw InputError("subject_alpha", "must be > 0 and finite");
    prior.subject_alpha = Eigen::MatrixXd::Constant(mdp.num_pairs(), num_symbols, *a);
    prior.subject_alpha_base = *a;
  } else {
    prior.subject_alpha = pair_rows(mdp, array_of(subject_alpha, "subject_alpha"), "subject_alpha");
    if (prior.subject_alpha.cols() != num_symbols)
      throw InputError("subject_alpha", "must have num_symbols = " + std::to_string(num_symbols) + " columns");
  }
  if (subject_alpha_default) {
    if (!(*subject_alpha_default >= 0.0) || !std::isfinite(*subject_alpha_default))
      throw InputError("subject_alpha_default", "must be >= 0 and finite");
    prior.subject_alpha_base = *subject_alpha_default;
  }
  if (const std::optional<double> a = number_of(confounder_alpha, "confounder_alpha")) {
    if (!(*a > 0.0) || !std::isfinite(*a)) throw InputError("confounder_alpha", "must be > 0 and finite");
    prior.confounder_alpha = Eigen::MatrixXd::Constant(num_confounders, num_symbols, *a);
  } else {
    const Array m = array_of(confounder_alpha, "confounder_alpha");
    if (m.ndim() != 2 || m.shape(0) != num_confounders || m.shape(1) != num_symbols) {
      throw InputError("confounder_alpha", "must be an (E, W) array with E = num_confounders and W = num_symbols");
    }
    prior.confounder_alpha = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        m.data(), m.shape(0), m.shape(1));
  }
  if (!prior.subject_alpha.allFinite() || (prior.subject_alpha.array() < 0.0).any())
    throw InputError("subject_alpha", "must be finite and >= 0");
  if (!prior.confounder_alpha.allFinite() || (prior.confounder_alpha.array() < 0.0).any())
    throw InputError("confounder_alpha", "must be finite and >= 0");
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) {
      if (mdp.is_terminal(s) || !mdp.available(s, a)) continue;
      if (!(prior.subject_alpha.row(mdp.pair(s, a)).sum() > 0.0)) {
        throw InputError("subject_alpha", "alpha of (" + std::to_string(s) + ", " + std::to_string(a) + ") sums to 0");
      }
    }
  }
  for (int e = 0; e < num_confounders; ++e) {
    if (!(prior.confounder_alpha.row(e).sum() > 0.0))
      throw InputError("confounder_alpha", "alpha of confounder " + std::to_string(e) + " sums to 0");
  }
  AlphaUpdate u;
  if (!parse_alpha_update(update, u)) throw InputError("update", "'" + update + "' is not posterior or paper");
  use_alpha_update(prior, u);
  if (!(c > 0.0 && c <= 1.0)) throw InputError("c", "must be in (0, 1]");
  prior.c = c;
  if (py::isinstance<py::str>(prior_strength)) {
    if (prior_strength.cast<std::string>() != "auto")
      throw InputError("prior_strength", "must be \"auto\" or a number");
  } else {
    const std::optional<double> given = number_of(prior_strength, "prior_strength");
    if (!given) throw InputError("prior_strength", "must be \"auto\" or a number");
    const double s = *given;
    if (!(s >= ObservationPrior::kMinStrength && s <= ObservationPrior::kMaxStrength)) {
      throw InputError("prior_strength", "must be in [" + std::to_string(ObservationPrior::kMinStrength) + ", " +
                                             std::to_string(ObservationPrior::kMaxStrength) + "]");
    }
    prior.automatic_strength = false;
    prior.strength = s;
  }
  if (learn) prior.learn = *learn;
  if (learn_eta) prior.learn_eta = *learn_eta;
  if (!(eta_strength > 0.0 && eta_strength <= 1e12)) throw InputError("eta_strength", "must be in (0, 1e12]");
  prior.eta_strength = eta_strength;
  if (!(unlisted_eta >= 0.0 && unlisted_eta < 1.0))
    throw InputError("unlisted_eta", "must be in [0, 1) (0: no catch-all source)");
  prior.unlisted_eta = unlisted_eta;
  return prior;
}

// read() with an InputError named after the file too ("path: field: what").
template <typename Read>
auto read_in_file(const std::string& path, Read&& read) {
  try {
    return read();
  } catch (const InputError& e) {
    throw InputError(path + (e.field().empty() ? "" : ": " + e.field()), e.message());
  }
}

void warn_each(const std::string& path, const std::vector<std::string>& warnings) {
  if (warnings.empty()) return;
  py::module_ w = py::module_::import("warnings");
  for (const auto& line : warnings) w.attr("warn")(path + ": " + line);
}

FlatObservations flat_of(const py::tuple& t) {
  if (t.size() != 6) throw InputError("observations", "internal: expected 6 parts");
  FlatObservations f{t[0].cast<IntArray>(), t[1].cast<Array>(), t[2].cast<IntArray>(),
                     t[3].cast<IntArray>(), std::nullopt,       std::nullopt};
  if (!t[4].is_none()) f.contexts = t[4].cast<IntArray>();
  if (!t[5].is_none()) f.ends_in_terminal = t[5].cast<std::vector<bool>>();
  return f;
}

// A Python value as a setting's JSON value (app::set checks it against the schema).
nlohmann::json json_of(const std::string& name, const py::handle& value) {
  if (value.is_none()) return nullptr;
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
  if (py::isinstance<py::int_>(value)) {
    if (value.cast<py::int_>() < py::int_(0)) return value.cast<std::int64_t>();
    return value.cast<std::uint64_t>();
  }
  if (py::isinstance<py::float_>(value)) return value.cast<double>();
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  throw InputError(name, "must be a number, a string, True, False or None");
}

// The estimator's settings (a dict of setting: value) as app::learn takes them.
app::LearnSettings settings_of(const py::dict& values) {
  app::LearnSettings settings;
  for (const auto& [key, value] : values) {
    const std::string name = py::str(key);
    app::set(settings, app::learn_setting(name), json_of(name, value));
  }
  return settings;
}

// The schema, for the estimators' keyword arguments and docstrings (python/hbirl/__init__.py).
py::list settings_schema() {
  static const char* const kTypes[] = {"integer", "number", "choice", "switch"};
  const app::LearnSettings defaults;
  py::list out;
  for (const app::Setting& s : app::learn_settings_schema()) {
    py::dict d;
    d["name"] = s.name;
    d["help"] = s.help;
    d["type"] = kTypes[static_cast<int>(s.type)];
    d["range"] = app::describe_range(s);
    const nlohmann::json value = s.get(defaults);
    if (value.is_null()) {
      d["default"] = py::none();
    } else if (value.is_boolean()) {
      d["default"] = value.get<bool>();
    } else if (value.is_number_unsigned()) {
      d["default"] = value.get<std::uint64_t>();
    } else if (value.is_number_integer()) {
      d["default"] = value.get<std::int64_t>();
    } else if (value.is_number()) {
      d["default"] = value.get<double>();
    } else {
      d["default"] = value.get<std::string>();
    }
    if (s.type == app::Setting::Type::kInteger) {
      d["min"] = py::int_(static_cast<std::int64_t>(s.min));
      d["max"] = s.max >= static_cast<long double>(std::numeric_limits<std::uint64_t>::max())
                     ? py::int_(std::numeric_limits<std::uint64_t>::max())
                     : py::int_(static_cast<std::int64_t>(s.max));
    }
    d["choices"] = s.choices;
    d["unset"] = s.optional ? py::object(py::str(s.unset_help)) : py::none();
    d["observations_only"] = s.hidden_data;
    out.append(d);
  }
  return out;
}

// MaxCausalEnt IRL from true trajectories (hbirl learn --from truth): app::learn_from_truth.
py::dict fit_maxcausalent(const Mdp& mdp, const std::vector<IntArray>& arrays, const py::dict& values) {
  const app::LearnSettings settings = settings_of(values);
  std::vector<Trajectory> truth = trajectories_of(mdp, arrays, "trajectories");
  LearnResult learned;
  {
    py::gil_scoped_release released;  // minutes on large MDPs: other Python threads run meanwhile
    learned = app::learn_from_truth(mdp, std::move(truth), settings).em;
  }
  py::dict out;
  out["theta"] = learned.theta;
  out["log_likelihood"] = learned.log_likelihood;
  return out;
}

}  // namespace
}  // namespace hbirl::python

PYBIND11_MODULE(_hbirl, m) {
  using namespace hbirl;
  using namespace hbirl::python;
  m.doc() = "hbirl's C++ core (use the hbirl package, which wraps it)";
  m.attr("__version__") = HBIRL_VERSION;
  // Bad input is a ValueError with the command line's one-line message (field: what is wrong).
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

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
      .def_property_readonly(
          "terminal",
          [](const Mdp& mdp) {
            std::vector<int> out;
            for (int s = 0; s < mdp.num_states; ++s) {
              if (mdp.is_terminal(s)) out.push_back(s);
            }
            return out;
          },
          "The terminal states.")
      .def(
          "transition_rows",
          [](const Mdp& mdp) {
            const Eigen::SparseMatrix<double, Eigen::RowMajor> t = mdp.transitions;
            Eigen::MatrixXd out(t.nonZeros(), 4);
            Eigen::Index k = 0;
            for (int r = 0; r < t.outerSize(); ++r) {
              for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(t, r); it; ++it, ++k) {
                out.row(k) << r / mdp.num_actions, r % mdp.num_actions, static_cast<double>(it.col()), it.value();
              }
            }
            return out;
          },
          "The transitions as (M, 4) rows [s, a, s', probability].")
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
      .def(
          "optimal_policy",
          [](const Mdp& mdp, const Array& reward) {
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
          },
          py::arg("reward"),
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

  py::class_<ObservationPrior>(
      m, "ObservationPrior",
      "Dirichlet priors of the observation model (paper §II): the subject's per (s, a), each confounding\n"
      "element's, and how they and eta are learned.")
      .def(py::init(&make_prior), py::arg("mdp"), py::arg("num_symbols"), py::arg("num_confounders"),
           py::arg("subject_alpha") = 1.0, py::arg("confounder_alpha") = 1.0,
           py::arg("subject_alpha_default") = py::none(), py::arg("update") = "posterior", py::arg("c") = 0.1,
           py::arg("prior_strength") = "auto", py::arg("learn") = py::none(), py::arg("learn_eta") = py::none(),
           py::arg("eta_strength") = 10.0, py::arg("unlisted_eta") = 0.0)
      .def_property_readonly("num_symbols", [](const ObservationPrior& p) { return p.num_symbols; })
      .def_property_readonly("num_confounders", [](const ObservationPrior& p) { return p.num_confounders; })
      .def_property_readonly("confounder_alpha", [](const ObservationPrior& p) { return p.confounder_alpha; })
      .def(
          "subject_alpha",
          [](const ObservationPrior& p, const Mdp& mdp) {
            if (p.subject_alpha.rows() != mdp.num_pairs()) throw InputError("mdp", "is not the MDP of this prior");
            return per_state_action_symbol(mdp, p.subject_alpha);
          },
          py::arg("mdp"), "The subject's alpha as an (S, A, W) array.")
      .def_property_readonly("update",
                             [](const ObservationPrior& p) { return std::string(alpha_update_name(p.update)); })
      .def_property_readonly("learn", [](const ObservationPrior& p) { return p.learn; })
      .def_property_readonly("learn_eta", [](const ObservationPrior& p) { return p.learn_eta; })
      .def_property_readonly("eta_strength", [](const ObservationPrior& p) { return p.eta_strength; })
      .def_property_readonly("unlisted_eta", [](const ObservationPrior& p) { return p.unlisted_eta; })
      .def_property_readonly("prior_strength", [](const ObservationPrior& p) {
        return p.automatic_strength ? py::object(py::str("auto")) : py::object(py::float_(p.strength));
      });

  m.def(
      "controlled_run_prior",
      [](const Mdp& mdp, const std::vector<IntArray>& truth, const py::tuple& observations, int num_symbols) {
        if (num_symbols < 1 || static_cast<long long>(mdp.num_pairs()) * num_symbols > (1LL << 28)) {
          throw InputError("num_symbols",
                           "must be at least 1, and num_states * num_actions * num_symbols at most 2^28");
        }
        ObservationPrior none;
        none.num_symbols = num_symbols;
        const std::vector<Trajectory> steps = trajectories_of(mdp, truth, "truth");
        std::vector<ObservedTrajectory> seen = observed_trajectories(flat_of(observations), none, mdp);
        py::gil_scoped_release released;
        try {
          return controlled_run_prior(mdp, steps, seen, num_symbols);
        } catch (const InputError& e) {  // named as the arguments are
          std::string field = e.field().rfind("ground_truth", 0) == 0 ? "truth" + e.field().substr(12) : e.field();
          if (field == "observations.num_symbols") field = "num_symbols";
          throw InputError(field, e.message());
        }
      },
      py::arg("mdp"), py::arg("truth"), py::arg("observations"), py::arg("num_symbols"));

  py::class_<Problem>(m, "Problem",
                      "A problem file (README.md \"Problem files\"): an MDP, names, demonstrations, true weights.")
      .def_property_readonly("mdp", [](const Problem& p) { return p.mdp; })
      .def_property_readonly("feature_names", [](const Problem& p) { return p.feature_names; })
      .def_property_readonly("state_names", [](const Problem& p) { return p.state_names; })
      .def_property_readonly("action_names", [](const Problem& p) { return p.action_names; })
      .def_property_readonly("true_weights", [](const Problem& p) { return p.true_weights; })
      .def(
          "truth_trajectories", [](const Problem& p) { return trajectories_to_arrays(p.truth_trajectories()); },
          "The demonstrations' true steps (the controlled run's left out), each a (T, 2) array of (state, action).")
      .def("_observations",
           [](const Problem& p) {
             std::vector<ObservedTrajectory> seen;
             {
               py::gil_scoped_release released;
               seen = problem_observations(p).trajectories;
             }
             return flat_observations(seen);
           })
      .def_property_readonly(
          "observation_prior",
          [](const Problem& p) {
            py::gil_scoped_release released;
            return problem_prior(p);
          },
          "The prior hbirl learn starts from: the file's observation_model, with the controlled run's counts as the\n"
          "subject's prior when the file has one.")
      .def(
          "save",
          [](const Problem& p, const std::string& path) {
            py::gil_scoped_release released;
            std::ofstream out(path);
            out << format_json(problem_to_json(p));
            if (!out.flush()) throw InputError(path, "could not be written");
          },
          py::arg("path"),
          "Write the problem file (README.md \"Problem files\"); hbirl load_problem and the CLI read it back.");
  m.def(
      "load_problem",
      [](const std::string& path) {
        std::vector<std::string> warnings;
        Problem p;
        {
          py::gil_scoped_release released;  // a large file takes seconds
          p = read_in_file(path, [&] { return read_problem_file(path, &warnings); });
        }
        warn_each(path, warnings);
        return p;
      },
      py::arg("path"),
      "Read and check a problem file; a bad file raises ValueError naming the file, the field and the reason.");
  m.def(
      "load_domain",
      [](const std::string& path) {
        std::vector<std::string> warnings;
        Problem p;
        {
          py::gil_scoped_release released;
          const DomainSpec d = read_in_file(path, [&] { return read_domain_file(path, &warnings); });
          p.mdp = d.mdp;
          p.state_names = d.state_names;
          p.action_names = d.action_names;
          p.feature_names = d.feature_names;
          p.observation_model = d.observation_model;
          p.true_weights = d.true_weights;
        }
        warn_each(path, warnings);
        return p;
      },
      py::arg("path"),
      "Read and check a domain file of the service set (README.md \"Your own task\") as a Problem without\n"
      "demonstrations: its MDP, names, stated observation prior and true weights.");
  m.def(
      "gridworld",
      [](const GridworldProblemOptions& o) {
        py::gil_scoped_release released;
        return gridworld_problem(o);
      },
      py::arg("options"));
  py::class_<GridworldProblemOptions>(m, "_GridworldOptions")
      .def(py::init<>())
      .def_readwrite("size", &GridworldProblemOptions::size)
      .def_readwrite("trajectories", &GridworldProblemOptions::trajectories)
      .def_readwrite("length", &GridworldProblemOptions::length)
      .def_readwrite("goal", &GridworldProblemOptions::goal)
      .def_readwrite("goal_weight", &GridworldProblemOptions::goal_weight)
      .def_readwrite("intended", &GridworldProblemOptions::intended)
      .def_readwrite("discount", &GridworldProblemOptions::discount)
      .def_readwrite("seed", &GridworldProblemOptions::seed)
      .def_readwrite("confounders", &GridworldProblemOptions::confounders)
      .def_readwrite("per_step", &GridworldProblemOptions::per_step)
      .def_readwrite("controlled", &GridworldProblemOptions::controlled)
      .def_property(
          "labeller_mass", [](const GridworldProblemOptions& o) { return o.labeller.mass; },
          [](GridworldProblemOptions& o, double v) { o.labeller.mass = v; })
      .def_property(
          "labeller_accuracy", [](const GridworldProblemOptions& o) { return o.labeller.accuracy; },
          [](GridworldProblemOptions& o, double v) { o.labeller.accuracy = v; });
  m.def("onion", [] {
    Problem p;
    p.mdp = onion::make_onion_mdp();
    p.state_names = onion::state_names();
    p.action_names = onion::action_names();
    p.feature_names = onion::feature_names();
    p.true_weights = onion::expert_weights();
    return p;
  });

  m.def(
      "causal_log_likelihood",
      [](const Mdp& mdp, const std::vector<IntArray>& trajectories, const Eigen::VectorXd& theta) {
        const Eigen::VectorXd w = theta_of(mdp, theta, "theta");
        const std::vector<Trajectory> steps = trajectories_of(mdp, trajectories, "trajectories");
        double value = 0.0;
        Eigen::VectorXd gradient(mdp.num_features());
        {
          py::gil_scoped_release released;
          CausalLikelihood objective(mdp, visit_counts(mdp, steps));
          objective.evaluate(w, &gradient);
          value = objective.log_likelihood();
          gradient *= objective.total_count();  // evaluate() gives d(L / M); L's own gradient
        }
        return py::make_tuple(value, gradient);
      },
      py::arg("mdp"), py::arg("trajectories"), py::arg("theta"),
      "The causal log-likelihood L(theta) of true trajectories (list of (T, 2) arrays) under the soft policy of\n"
      "theta, and its exact gradient (K,): what MaxCausalEntIRL maximises, for an optimiser of your own\n"
      "(docs/MODEL.md).");
  m.def("_fit_maxcausalent", &fit_maxcausalent, py::arg("mdp"), py::arg("trajectories"), py::arg("settings"));
  m.def("_learn_settings", &settings_schema,
        "Every learning setting (app/learn_settings.hpp): name, help, type, range, default, choices, what unset means");

  py::class_<FittedHierarchical>(m, "_FittedHierarchical")
      .def_readonly("theta", &FittedHierarchical::theta)
      .def_readonly("log_likelihood", &FittedHierarchical::log_likelihood)
      .def_readonly("em_iterations", &FittedHierarchical::em_iterations)
      .def_readonly("converged", &FittedHierarchical::converged)
      .def_readonly("status", &FittedHierarchical::status)
      .def_readonly("history_log_likelihood", &FittedHierarchical::history_log_likelihood)
      .def_readonly("history_objective", &FittedHierarchical::history_objective)
      .def_readonly("history_prior_strength", &FittedHierarchical::history_prior_strength)
      .def_property_readonly("history_theta",
                             [](const FittedHierarchical& f) {
                               Eigen::MatrixXd out(static_cast<Eigen::Index>(f.history_theta.size()), f.theta.size());
                               for (size_t i = 0; i < f.history_theta.size(); ++i)
                                 out.row(static_cast<Eigen::Index>(i)) = f.history_theta[i].transpose();
                               return out;
                             })
      .def_readonly("refined", &FittedHierarchical::refined)
      .def_property_readonly("subject", [](const FittedHierarchical& f) { return f.model.subject; })
      .def_property_readonly("confounders", [](const FittedHierarchical& f) { return f.model.confounders; })
      .def_property_readonly("learned_eta",
                             [](const FittedHierarchical& f) -> py::object {
                               if (!f.learned_eta) return py::none();
                               py::dict d;
                               d["stated"] = Eigen::MatrixXd(f.learned_eta->stated);
                               d["learned"] = Eigen::MatrixXd(f.learned_eta->learned);
                               d["observations"] = f.learned_eta->observations;
                               return d;
                             })
      .def_property_readonly("unlisted_source", [](const FittedHierarchical& f) { return f.refined.unlisted_added; })
      .def_property_readonly("mcmc_diagnostics", [](const FittedHierarchical& f) -> py::object {
        if (!f.mcmc) return py::none();
        py::dict d;
        const bool checked = f.mcmc->quantities > 0;
        d["worst_rhat"] = checked ? py::object(py::float_(f.mcmc->worst_rhat)) : py::none();
        d["worst_bulk_ess"] = checked ? py::object(py::float_(f.mcmc->worst_bulk_ess)) : py::none();
        d["quantities"] = f.mcmc->quantities;
        d["chains"] = f.mcmc->chains;
        d["converged"] = f.mcmc->converged();
        return d;
      });

  m.def(
      "_fit_hierarchical",
      [](const Mdp& mdp, const py::tuple& observations, const ObservationPrior& prior, const py::dict& values) {
        const app::LearnSettings settings = settings_of(values);
        app::check_prior_fits(mdp, prior);
        const std::vector<ObservedTrajectory> seen = observed_trajectories(flat_of(observations), prior, mdp);
        py::gil_scoped_release released;
        return fit_hierarchical(mdp, seen, prior, settings);
      },
      py::arg("mdp"), py::arg("observations"), py::arg("prior"), py::arg("settings"));
  m.def(
      "_posterior",
      [](const Mdp& mdp, const FittedHierarchical& fit, const py::tuple& observations) {
        check_fitted_on(mdp, fit);
        const std::vector<ObservedTrajectory> seen = observed_trajectories(flat_of(observations), fit.given, mdp);
        Posteriors post;
        {
          py::gil_scoped_release released;
          post = posteriors(mdp, fit, seen);
        }
        py::list marginals, log_likelihood;
        long long n = 0;
        for (const auto& t : post.trajectories) n += t.sources.rows();
        const Eigen::Index sources = post.trajectories.empty() ? 1 : post.trajectories.front().sources.cols();
        Eigen::MatrixXd all_sources(n, sources);
        Eigen::Index row = 0;
        for (const auto& t : post.trajectories) {
          py::array_t<double> mt(std::vector<py::ssize_t>{t.marginals.rows(), mdp.num_states, mdp.num_actions});
          auto v = mt.mutable_unchecked<3>();
          for (Eigen::Index k = 0; k < t.marginals.rows(); ++k) {
            for (int s = 0; s < mdp.num_states; ++s) {
              for (int a = 0; a < mdp.num_actions; ++a) v(k, s, a) = t.marginals(k, mdp.pair(s, a));
            }
          }
          marginals.append(mt);
          log_likelihood.append(t.log_likelihood);
          if (t.sources.rows() > 0) all_sources.middleRows(row, t.sources.rows()) = t.sources;
          row += t.sources.rows();
        }
        return py::make_tuple(marginals, all_sources, log_likelihood);
      },
      py::arg("mdp"), py::arg("fit"), py::arg("observations"));
  m.def(
      "_log_likelihoods",
      [](const Mdp& mdp, const FittedHierarchical& fit, const py::tuple& observations) {
        check_fitted_on(mdp, fit);
        const std::vector<ObservedTrajectory> seen = observed_trajectories(flat_of(observations), fit.given, mdp);
        py::gil_scoped_release released;
        return log_likelihoods(mdp, fit, seen);
      },
      py::arg("mdp"), py::arg("fit"), py::arg("observations"));
  bind_recording(m);
}
