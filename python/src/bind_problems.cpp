// hbirl._hbirl's problems (bindings.hpp): problem and domain files, and the paper's
// Gridworld and onion sorting as problems.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <fstream>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "learner/input_error.hpp"
#include "problem/domain_file.hpp"
#include "problem/json_format.hpp"
#include "problem/problem_file.hpp"
#include "problem/problem_observations.hpp"
#include "sim_driver/gridworld/problem_file.hpp"
#include "sim_driver/onion/onion.hpp"

namespace hbirl::python {
namespace {

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

}  // namespace

void bind_problem(py::module_& m) {
  py::class_<Problem>(m, "Problem",
                      "A problem file (docs/files.md \"Problem files\"): an MDP, names, demonstrations, true weights.")
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
            std::ofstream out(path, std::ios::binary);
            write_problem(out, p);
            if (!out.flush()) throw InputError(path, "could not be written");
          },
          py::arg("path"),
          "Write the problem file (docs/files.md \"Problem files\"); hbirl load_problem and the CLI read it back.");
}

void bind_problem_files(py::module_& m) {
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
      "Read and check a domain file of the service set (docs/your-task.md \"Your own task\") as a Problem without\n"
      "demonstrations: its MDP, names, stated observation prior and true weights.");
}

void bind_example_problems(py::module_& m) {
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
}

}  // namespace hbirl::python
