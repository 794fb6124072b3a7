// hbirl._hbirl: the C++ core for Python (pybind11), numpy arrays in and out. The package
// around it (python/hbirl/__init__.py) adds the scikit-learn-style estimators; shapes and
// conventions are documented there and in README.md "Python".
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "learner/estep.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/mdp.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"
#include "problem/problem_file.hpp"

namespace py = pybind11;

namespace hbirl::python {
namespace {

using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<long long, py::array::c_style | py::array::forcecast>;

// The dense (S, A, S') transitions and (S, A, K) features of an MDP (README.md "Python"):
// an (s, a) row of zeros is an impossible action; terminal states take none. Checked as
// a problem file is (Mdp::validate), so bad input is a ValueError naming what is wrong.
Mdp mdp_from_arrays(const Array& transitions, const Array& features, const std::optional<Eigen::VectorXd>& start,
                    const std::vector<int>& terminal, double discount) {
  if (transitions.ndim() != 3 || transitions.shape(2) != transitions.shape(0) || transitions.shape(0) < 1 || transitions.shape(1) < 1) {
    throw InputError("transitions", "must be an (S, A, S) array with S, A >= 1");
  }
  const auto S = static_cast<int>(transitions.shape(0)), A = static_cast<int>(transitions.shape(1));
  if (features.ndim() != 3 || features.shape(0) != S || features.shape(1) != A) {
    throw InputError("features", "must be an (S, A, K) array with the transitions' S and A");
  }
  const auto K = static_cast<int>(features.shape(2));
  std::vector<char> is_terminal(static_cast<size_t>(S), 0);
  for (int s : terminal) {
    if (s < 0 || s >= S) throw InputError("terminal", "state " + std::to_string(s) + " is not in [0, " + std::to_string(S - 1) + "]");
    is_terminal[static_cast<size_t>(s)] = 1;
  }
  const auto p = transitions.unchecked<3>();
  std::vector<TransitionEntry> entries;
  for (int s = 0; s < S; ++s) {
    if (is_terminal[static_cast<size_t>(s)]) continue;
    for (int a = 0; a < A; ++a) {
      for (int t = 0; t < S; ++t) {
        if (p(s, a, t) != 0.0) entries.push_back({s, a, t, p(s, a, t)});
      }
    }
  }
  const auto f = features.unchecked<3>();
  std::vector<FeatureEntry> phi;
  for (int s = 0; s < S; ++s) {
    for (int a = 0; a < A; ++a) {
      for (int k = 0; k < K; ++k) {
        if (f(s, a, k) != 0.0) phi.push_back({s, a, k, f(s, a, k)});
      }
    }
  }
  Eigen::VectorXd d = Eigen::VectorXd::Zero(S);
  if (start) {
    if (start->size() != S) throw InputError("start", "must have one probability per state");
    d = *start;
  } else {  // uniform over the non-terminal states, as in a problem file
    for (int s = 0; s < S; ++s) d[s] = is_terminal[static_cast<size_t>(s)] ? 0.0 : 1.0;
    if (d.sum() == 0.0) throw InputError("terminal", "every state is terminal");
    d /= d.sum();
  }
  try {
    Mdp mdp = make_mdp(S, A, K, entries, phi, d, terminal, discount);
    mdp.validate();
    return mdp;
  } catch (const InputError& e) {  // named as the arguments are ("transitions", not a file's "mdp.transitions")
    const std::string field = e.field().rfind("mdp.", 0) == 0 ? e.field().substr(4) : e.field();
    throw InputError(field, e.message());
  }
}

Eigen::VectorXd theta_of(const Mdp& mdp, const Eigen::VectorXd& theta, const std::string& name) {
  if (theta.size() != mdp.num_features()) {
    throw InputError(name, "has " + std::to_string(theta.size()) + " weights, the MDP " + std::to_string(mdp.num_features()) + " features");
  }
  if (!theta.allFinite()) throw InputError(name, "must be finite");
  return theta;
}

// (S, A) from a per-pair vector (pair = s * A + a).
Eigen::MatrixXd per_state_action(const Mdp& mdp, const Eigen::VectorXd& pairs) {
  Eigen::MatrixXd out(mdp.num_states, mdp.num_actions);
  for (int s = 0; s < mdp.num_states; ++s) {
    for (int a = 0; a < mdp.num_actions; ++a) out(s, a) = pairs[mdp.pair(s, a)];
  }
  return out;
}

// Trajectories as (T, 2) integer arrays of (state, action).
std::vector<Trajectory> trajectories_of(const Mdp& mdp, const std::vector<IntArray>& arrays) {
  if (arrays.empty()) throw InputError("trajectories", "none given");
  std::vector<Trajectory> out;
  for (size_t i = 0; i < arrays.size(); ++i) {
    const IntArray& a = arrays[i];
    const std::string name = "trajectories[" + std::to_string(i) + "]";
    if (a.ndim() != 2 || a.shape(1) != 2 || a.shape(0) < 1) throw InputError(name, "must be a (T, 2) array of (state, action), T >= 1");
    const auto v = a.unchecked<2>();
    Trajectory t;
    for (py::ssize_t k = 0; k < a.shape(0); ++k) {
      const long long s = v(k, 0), act = v(k, 1);
      if (s < 0 || s >= mdp.num_states || act < 0 || act >= mdp.num_actions) {
        throw InputError(name, "step " + std::to_string(k) + ": (" + std::to_string(s) + ", " + std::to_string(act) +
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

// MaxCausalEnt IRL from true trajectories (hbirl learn --from truth): HiddenDataEM with the
// truth as its E-step, so the same code and defaults as the command line.
py::dict fit_maxcausalent(const Mdp& mdp, const std::vector<IntArray>& arrays, const std::string& optimizer, double l2,
                          int restarts, std::uint64_t seed, int max_iterations, double tolerance, int threads) {
  if (optimizer != "lbfgs" && optimizer != "eg") throw InputError("optimizer", "'" + optimizer + "' is not lbfgs or eg");
  if (!(l2 >= 0.0) || !std::isfinite(l2)) throw InputError("l2", "must be finite and >= 0");
  if (restarts < 1) throw InputError("restarts", "must be at least 1");
  if (max_iterations < 1) throw InputError("max_iterations", "must be at least 1");
  if (!(tolerance > 0.0)) throw InputError("tolerance", "must be > 0");
  if (threads < 0) throw InputError("threads", "must be >= 0 (0: one per core)");
  std::vector<Trajectory> truth = trajectories_of(mdp, arrays);
  LearnResult learned;
  {
    py::gil_scoped_release released;  // minutes on large MDPs: other Python threads run meanwhile
    LearnOptions options;
    options.optimizer.kind = optimizer == "eg" ? OptimizerKind::kExponentiatedGradient : OptimizerKind::kLbfgs;
    options.optimizer.max_iterations = max_iterations;
    options.optimizer.gradient_tolerance = tolerance;
    options.l2 = l2;
    options.restarts = restarts;
    options.seed = seed;
    options.threads = threads;
    const TruthEStep estep(mdp, std::move(truth));
    learned = learn_reward(mdp, estep, options);
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

  py::class_<Mdp>(m, "Mdp", "A finite MDP: states, actions, transitions, features, start distribution, terminal states, discount.")
      .def(py::init(&mdp_from_arrays), py::arg("transitions"), py::arg("features"), py::arg("start") = py::none(),
           py::arg("terminal") = std::vector<int>{}, py::arg("discount") = 0.95,
           "transitions: (S, A, S) array of Pr(s' | s, a) (a row of zeros: the action is impossible; terminal\n"
           "states' rows are ignored); features: (S, A, K) array phi(s, a); start: (S,) distribution (default:\n"
           "uniform over the non-terminal states); terminal: list of terminal states; discount in [0, 1).")
      .def_property_readonly("num_states", [](const Mdp& mdp) { return mdp.num_states; })
      .def_property_readonly("num_actions", [](const Mdp& mdp) { return mdp.num_actions; })
      .def_property_readonly("num_features", &Mdp::num_features)
      .def_property_readonly("discount", [](const Mdp& mdp) { return mdp.discount; })
      .def_property_readonly("start", [](const Mdp& mdp) { return mdp.start; })
      .def(
          "reward", [](const Mdp& mdp, const Eigen::VectorXd& theta) { return per_state_action(mdp, mdp.reward(theta_of(mdp, theta, "theta"))); },
          py::arg("theta"), "R(s, a) = theta . phi(s, a) as an (S, A) array.")
      .def(
          "soft_policy",
          [](const Mdp& mdp, const Eigen::VectorXd& theta) {
            const Eigen::VectorXd r = mdp.reward(theta_of(mdp, theta, "theta"));
            py::gil_scoped_release released;
            return per_state_action(mdp, soft_value_iteration(mdp, r).policy);
          },
          py::arg("theta"), "The MaxCausalEnt (soft) policy pi(a | s) for reward weights theta, an (S, A) array (0 on terminal states).")
      .def(
          "soft_values",
          [](const Mdp& mdp, const Eigen::VectorXd& theta) {
            const Eigen::VectorXd r = mdp.reward(theta_of(mdp, theta, "theta"));
            py::gil_scoped_release released;
            return Eigen::VectorXd(soft_value_iteration(mdp, r).value);
          },
          py::arg("theta"), "The soft values V(s) for reward weights theta, an (S,) array (0 at terminal states).");

  m.def(
      "ile",
      [](const Mdp& mdp, const Eigen::VectorXd& true_theta, const Eigen::VectorXd& learned_theta) {
        const Eigen::VectorXd t = theta_of(mdp, true_theta, "true_theta"), l = theta_of(mdp, learned_theta, "learned_theta");
        py::gil_scoped_release released;
        return inverse_learning_error(mdp, t, l).ile;
      },
      py::arg("mdp"), py::arg("true_theta"), py::arg("learned_theta"),
      "Inverse learning error: the L1 distance between the values of the optimal policies of the true and the\n"
      "learned reward, both under the true reward (paper §Experiments).");

  py::class_<Problem>(m, "Problem", "A problem file (README.md \"Problem files\"): an MDP, names, demonstrations, true weights.")
      .def_property_readonly("mdp", [](const Problem& p) { return p.mdp; })
      .def_property_readonly("feature_names", [](const Problem& p) { return p.feature_names; })
      .def_property_readonly("state_names", [](const Problem& p) { return p.state_names; })
      .def_property_readonly("action_names", [](const Problem& p) { return p.action_names; })
      .def_property_readonly("true_weights", [](const Problem& p) { return p.true_weights; })
      .def(
          "truth_trajectories", [](const Problem& p) { return trajectories_to_arrays(p.truth_trajectories()); },
          "The demonstrations' true steps (the controlled run's left out), each a (T, 2) array of (state, action).");
  m.def(
      "load_problem",
      [](const std::string& path) {
        std::vector<std::string> warnings;
        Problem p;
        try {
          p = read_problem_file(path, &warnings);
        } catch (const InputError& e) {
          throw InputError(path + (e.field().empty() ? "" : ": " + e.field()), e.message());
        }
        if (!warnings.empty()) {
          py::module_ w = py::module_::import("warnings");
          for (const auto& line : warnings) w.attr("warn")(path + ": " + line);
        }
        return p;
      },
      py::arg("path"), "Read and check a problem file; a bad file raises ValueError naming the file, the field and the reason.");

  m.def("_fit_maxcausalent", &fit_maxcausalent, py::arg("mdp"), py::arg("trajectories"), py::arg("optimizer"), py::arg("l2"),
        py::arg("restarts"), py::arg("seed"), py::arg("max_iterations"), py::arg("tolerance"), py::arg("threads"));
}
