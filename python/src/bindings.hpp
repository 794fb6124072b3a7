#pragma once
// The parts of hbirl._hbirl (module.cpp), by topic. PYBIND11_MODULE calls them in the
// order below: a definition's docstring names the classes defined before it, so the order
// is part of what Python sees.
#include <pybind11/pybind11.h>

#include "arrays.hpp"

namespace hbirl::python {

void bind_mdp(py::module_& m);                // Mdp, ile
void bind_observation_prior(py::module_& m);  // ObservationPrior, controlled_run_prior
void bind_problem(py::module_& m);            // Problem
void bind_problem_files(py::module_& m);      // load_problem, load_domain
void bind_example_problems(py::module_& m);   // gridworld, _GridworldOptions, onion
void bind_maxcausalent(py::module_& m);       // causal_log_likelihood, _fit_maxcausalent, _learn_settings
void bind_hierarchical(py::module_& m);       // _FittedHierarchical, _fit_hierarchical, _posterior, _log_likelihoods
void bind_recording(py::module_& m);          // _read_log (app/recorded_problem.hpp)
void bind_bus(py::module_& m);                // _Bus, _Sensor (Python sensors)

}  // namespace hbirl::python
