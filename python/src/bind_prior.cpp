// hbirl._hbirl's ObservationPrior (bindings.hpp): the Dirichlet priors of the observation
// model from numbers or arrays, and the prior a controlled run gives.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "learner/controlled_prior.hpp"
#include "learner/input_error.hpp"

namespace hbirl::python {
namespace {

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

// A prior of num_symbols symbols and num_confounders confounders, its alphas not yet set;
// bounded before anything is allocated.
ObservationPrior sized_prior(const Mdp& mdp, int num_symbols, int num_confounders) {
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
  return prior;
}

// subject_alpha_default is the base of the posterior update's power prior (a problem
// file's subject_alpha_default, observations.hpp): counts above it are what the prior
// strength weighs. A number given for subject_alpha is its own base, as in a file that
// gives only subject_alpha_default.
void set_subject_alpha(ObservationPrior& prior, const Mdp& mdp, const py::object& subject_alpha,
                       std::optional<double> subject_alpha_default) {
  const int num_symbols = prior.num_symbols;
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
}

void set_confounder_alpha(ObservationPrior& prior, const py::object& confounder_alpha) {
  const int num_symbols = prior.num_symbols, num_confounders = prior.num_confounders;
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
}

// Every alpha finite and >= 0, and each possible (s, a)'s and each confounder's above 0 in sum.
void check_alphas(const ObservationPrior& prior, const Mdp& mdp) {
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
  for (int e = 0; e < prior.num_confounders; ++e) {
    if (!(prior.confounder_alpha.row(e).sum() > 0.0))
      throw InputError("confounder_alpha", "alpha of confounder " + std::to_string(e) + " sums to 0");
  }
}

// The end sensor's prior (docs/MODEL.md "Sensors that see the end"): num_end_symbols
// symbols (0: none) and alpha per terminal state, a number (every terminal state's every
// symbol; its own base, as a problem file's alpha_default) or an (S, K) array whose
// non-terminal rows are 0; checked as a problem file's end_sensor is.
void set_end_alpha(ObservationPrior& prior, const Mdp& mdp, int num_end_symbols, const py::object& given_alpha,
                   std::optional<double> end_alpha_default) {
  if (num_end_symbols == 0) {
    if (!given_alpha.is_none() || end_alpha_default)
      throw InputError(given_alpha.is_none() ? "end_alpha_default" : "end_alpha",
                       "is given, but num_end_symbols is 0 (no end sensor)");
    return;
  }
  const py::object end_alpha = given_alpha.is_none() ? py::object(py::float_(1.0)) : given_alpha;
  const int K = num_end_symbols;
  if (K < 0 || K > kMaxEndSymbols)
    throw InputError("num_end_symbols", "must be in [0, " + std::to_string(kMaxEndSymbols) + "] (0: no end sensor)");
  if (std::find(mdp.terminal.begin(), mdp.terminal.end(), 1) == mdp.terminal.end())
    throw InputError("num_end_symbols", "is given, but the MDP has no terminal states for an end sensor to see");
  if (static_cast<long long>(mdp.num_states) * K > (1LL << 28))
    throw InputError("num_end_symbols", "num_states * num_end_symbols is more than an end sensor may take (2^28)");
  if (const std::optional<double> a = number_of(end_alpha, "end_alpha")) {
    if (!(*a > 0.0) || !std::isfinite(*a)) throw InputError("end_alpha", "must be > 0 and finite");
    prior.end_alpha = Eigen::MatrixXd::Zero(mdp.num_states, K);
    for (int s = 0; s < mdp.num_states; ++s) {
      if (mdp.is_terminal(s)) prior.end_alpha.row(s).setConstant(*a);
    }
    prior.end_alpha_base = *a;
  } else {
    const Array m = array_of(end_alpha, "end_alpha");
    if (m.ndim() != 2 || m.shape(0) != mdp.num_states || m.shape(1) != K)
      throw InputError("end_alpha", "must be an (S, K) array with the MDP's S = " + std::to_string(mdp.num_states) +
                                        " and K = num_end_symbols = " + std::to_string(K));
    prior.end_alpha = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        m.data(), m.shape(0), m.shape(1));
  }
  if (end_alpha_default) {
    if (!(*end_alpha_default >= 0.0) || !std::isfinite(*end_alpha_default))
      throw InputError("end_alpha_default", "must be >= 0 and finite");
    prior.end_alpha_base = *end_alpha_default;
  }
  if (!prior.end_alpha.allFinite() || (prior.end_alpha.array() < 0.0).any())
    throw InputError("end_alpha", "must be finite and >= 0");
  for (int s = 0; s < mdp.num_states; ++s) {
    const double sum = prior.end_alpha.row(s).sum();
    if (mdp.is_terminal(s) && !(sum > 0.0))
      throw InputError("end_alpha", "alpha of terminal state " + std::to_string(s) + " sums to 0");
    if (!mdp.is_terminal(s) && sum != 0.0)
      throw InputError("end_alpha", "state " + std::to_string(s) + " is not terminal; the end sensor sees only those");
  }
}

// "auto", or a number in the range the strength may take.
void set_prior_strength(ObservationPrior& prior, const py::object& prior_strength) {
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
}

// An observation prior from arrays (docs/python.md "Python"): the subject's alpha as a number
// (every (s, a) and symbol) or an (S, A, W) array, the confounders' as a number or an
// (E, W) array; checked as a problem file's observation_model is.
ObservationPrior make_prior(const Mdp& mdp, int num_symbols, int num_confounders, const py::object& subject_alpha,
                            const py::object& confounder_alpha, std::optional<double> subject_alpha_default,
                            const std::string& update, double c, const py::object& prior_strength,
                            std::optional<bool> learn, std::optional<bool> learn_eta, double eta_strength,
                            double unlisted_eta, int num_end_symbols, const py::object& end_alpha,
                            std::optional<double> end_alpha_default, bool tie_actions) {
  ObservationPrior prior = sized_prior(mdp, num_symbols, num_confounders);
  set_subject_alpha(prior, mdp, subject_alpha, subject_alpha_default);
  set_confounder_alpha(prior, confounder_alpha);
  check_alphas(prior, mdp);
  set_end_alpha(prior, mdp, num_end_symbols, end_alpha, end_alpha_default);
  AlphaUpdate u;
  if (!parse_alpha_update(update, u)) throw InputError("update", "'" + update + "' is not posterior or paper");
  use_alpha_update(prior, u);
  if (!(c > 0.0 && c <= 1.0)) throw InputError("c", "must be in (0, 1]");
  prior.c = c;
  set_prior_strength(prior, prior_strength);
  if (learn) prior.learn = *learn;
  if (learn_eta) prior.learn_eta = *learn_eta;
  if (!(eta_strength > 0.0 && eta_strength <= 1e12)) throw InputError("eta_strength", "must be in (0, 1e12]");
  prior.eta_strength = eta_strength;
  if (!(unlisted_eta >= 0.0 && unlisted_eta < 1.0))
    throw InputError("unlisted_eta", "must be in [0, 1) (0: no catch-all source)");
  prior.unlisted_eta = unlisted_eta;
  prior.tie_actions = tie_actions;
  return prior;
}

}  // namespace

void bind_observation_prior(py::module_& m) {
  py::class_<ObservationPrior>(
      m, "ObservationPrior",
      "Dirichlet priors of the observation model (paper §II): the subject's per (s, a), each confounding\n"
      "element's, and how they and eta are learned.")
      .def(py::init(&make_prior), py::arg("mdp"), py::arg("num_symbols"), py::arg("num_confounders"),
           py::arg("subject_alpha") = 1.0, py::arg("confounder_alpha") = 1.0,
           py::arg("subject_alpha_default") = py::none(), py::arg("update") = "posterior", py::arg("c") = 0.1,
           py::arg("prior_strength") = "auto", py::arg("learn") = py::none(), py::arg("learn_eta") = py::none(),
           py::arg("eta_strength") = 10.0, py::arg("unlisted_eta") = 0.0, py::arg("num_end_symbols") = 0,
           py::arg("end_alpha") = py::none(), py::arg("end_alpha_default") = py::none(), py::arg("tie_actions") = false)
      .def_property_readonly("num_symbols", [](const ObservationPrior& p) { return p.num_symbols; })
      .def_property_readonly("num_confounders", [](const ObservationPrior& p) { return p.num_confounders; })
      .def_property_readonly("confounder_alpha", [](const ObservationPrior& p) { return p.confounder_alpha; })
      .def_property_readonly("num_end_symbols", [](const ObservationPrior& p) { return p.num_end_symbols(); })
      .def_property_readonly(
          "end_alpha",
          [](const ObservationPrior& p) -> py::object {
            return p.num_end_symbols() == 0 ? py::none() : py::cast(p.end_alpha);
          },
          "The end sensor's alpha as an (S, K) array (rows of terminal states), or None: no end sensor.")
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
      .def_property_readonly(
          "tie_actions", [](const ObservationPrior& p) { return p.tie_actions; },
          "Whether the subject's prior is tied across each state's actions (docs/MODEL.md).")
      .def_property_readonly("prior_strength", [](const ObservationPrior& p) {
        return p.automatic_strength ? py::object(py::str("auto")) : py::object(py::float_(p.strength));
      });

  m.attr("_MAX_END_REPORTS") = kMaxEndReports;  // one ending's reports at most (learner/observations.hpp)
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
}

}  // namespace hbirl::python
