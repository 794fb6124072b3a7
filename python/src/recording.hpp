#pragma once
// hbirl.read_log's C++ side (recording.cpp).
#include <pybind11/pybind11.h>

namespace hbirl::python {

void bind_recording(pybind11::module_& m);

}  // namespace hbirl::python
