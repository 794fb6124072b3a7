// hbirl._hbirl: the C++ core for Python (pybind11), numpy arrays in and out. The package
// around it (python/hbirl/__init__.py) adds the scikit-learn-style estimators and the
// input forms numpy cannot check alone; shapes and conventions are documented there and
// in docs/python.md "Python". Every long call releases the GIL. The definitions are in the
// bind_*.cpp files, by topic (bindings.hpp).
#include <pybind11/pybind11.h>

#include <exception>

#include "bindings.hpp"
#include "learner/input_error.hpp"

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
  bind_mdp(m);
  bind_observation_prior(m);
  bind_problem(m);
  bind_problem_files(m);
  bind_example_problems(m);
  bind_maxcausalent(m);
  bind_hierarchical(m);
  bind_recording(m);
  bind_bus(m);
}
