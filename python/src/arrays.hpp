#pragma once
// numpy <-> hbirl conversions of the Python package (docs/python.md "Python"): shapes are checked
// before anything is allocated, and bad input is an InputError (a ValueError in Python)
// naming the argument as the Python caller wrote it.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <optional>
#include <string>
#include <vector>

#include "learner/mdp.hpp"
#include "learner/observations.hpp"
#include "learner/trajectory.hpp"

namespace hbirl::python {

namespace py = pybind11;
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<long long, py::array::c_style | py::array::forcecast>;

// Observations in the flat form (hmmlearn's `lengths`): observation n has symbol
// symbols[n], source distribution eta[n] (1 + |E| entries, summing to 1) and optional
// context contexts[n]; it was made at step step_index[n] (nondecreasing, counting the
// steps of every trajectory in turn); trajectory i has lengths[i] steps, the last one
// leading into a terminal state when ends_in_terminal[i]. Of that end, end_state[i] is the
// terminal state entered when known (-1: not) and end_symbols[i] an end sensor's reports
// (docs/MODEL.md "Sensors that see the end").
struct FlatObservations {
  IntArray symbols;
  Array eta;
  IntArray step_index;
  IntArray lengths;
  std::optional<IntArray> contexts;
  std::optional<std::vector<bool>> ends_in_terminal;
  std::optional<std::vector<IntArray>> end_symbols;
  std::optional<IntArray> end_state;
};

// The trajectories of `flat`, checked against `prior` (symbols, sources) with eta rows
// normalised as a problem file's are (within 1e-6 of summing to 1); ends_in_terminal
// defaults as in a problem file (true when the MDP has terminal states); a context of -1
// is none (for a whole trajectory); end reports are checked against the prior's end sensor.
std::vector<ObservedTrajectory> observed_trajectories(const FlatObservations& flat, const ObservationPrior& prior,
                                                      const Mdp& mdp);
// And back: (symbols, eta, step_index, lengths, contexts or None, ends_in_terminal,
// end_symbols or None, end_state or None).
py::tuple flat_observations(const std::vector<ObservedTrajectory>& trajectories);
// The flat form from that tuple (the package passes observations so).
FlatObservations flat_of(const py::tuple& t);

// Per-pair vectors / matrices as (S, A) / (S, A, W) arrays (pair = s * A + a) and back.
py::array_t<double> per_state_action(const Mdp& mdp, const Eigen::VectorXd& pairs);
py::array_t<double> per_state_action_symbol(const Mdp& mdp, const Eigen::MatrixXd& rows);
Eigen::MatrixXd pair_rows(const Mdp& mdp, const Array& sa_w, const std::string& name);

// Trajectories as (T, 2) integer arrays of (state, action), and back.
std::vector<Trajectory> trajectories_of(const Mdp& mdp, const std::vector<IntArray>& arrays, const std::string& name);
py::list trajectories_to_arrays(const std::vector<Trajectory>& trajectories);

// theta with the MDP's K finite weights.
Eigen::VectorXd theta_of(const Mdp& mdp, const Eigen::VectorXd& theta, const std::string& name);

}  // namespace hbirl::python
