// hbirl._hbirl's estimators' C++ side (bindings.hpp): MaxCausalEnt IRL from true
// trajectories and the hierarchical model from observations, with the settings schema
// their keyword arguments are made from.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "app/learn.hpp"
#include "bindings.hpp"
#include "hierarchical.hpp"
#include "learner/input_error.hpp"
#include "learner/maxcausalent.hpp"

namespace hbirl::python {
namespace {

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
  std::optional<app::Learned> learned;
  {
    py::gil_scoped_release released;  // minutes on large MDPs: other Python threads run meanwhile
    learned.emplace(app::learn_from_truth(mdp, std::move(truth), settings));
  }
  py::dict out;
  out["theta"] = learned->em.theta;
  out["log_likelihood"] = learned->em.log_likelihood;
  out["posterior"] = learned->posterior ? py::object(py::str(app::posterior_summary(*learned).dump())) : py::none();
  return out;
}

// The fitted model's posterior of `observations`: (marginals, a (T, S, A) array per
// trajectory; sources, (N, 1 + |E|) over all observations; log-likelihood per trajectory).
py::tuple posterior_arrays(const Mdp& mdp, const FittedHierarchical& fit, const py::tuple& observations) {
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
}

}  // namespace

void bind_maxcausalent(py::module_& m) {
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
}

void bind_hierarchical(py::module_& m) {
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
      .def_property_readonly("posterior",
                             [](const FittedHierarchical& f) -> py::object {
                               return f.posterior.empty() ? py::none() : py::object(py::str(f.posterior));
                             })
      .def_property_readonly("subject", [](const FittedHierarchical& f) { return f.model.subject; })
      .def_property_readonly("confounders", [](const FittedHierarchical& f) { return f.model.confounders; })
      .def_property_readonly("end",
                             [](const FittedHierarchical& f) -> py::object {
                               return f.model.end.size() == 0 ? py::none() : py::cast(f.model.end);
                             })
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
  m.def("_posterior", &posterior_arrays, py::arg("mdp"), py::arg("fit"), py::arg("observations"));
  m.def(
      "_log_likelihoods",
      [](const Mdp& mdp, const FittedHierarchical& fit, const py::tuple& observations) {
        check_fitted_on(mdp, fit);
        const std::vector<ObservedTrajectory> seen = observed_trajectories(flat_of(observations), fit.given, mdp);
        py::gil_scoped_release released;
        return log_likelihoods(mdp, fit, seen);
      },
      py::arg("mdp"), py::arg("fit"), py::arg("observations"));
}

}  // namespace hbirl::python
