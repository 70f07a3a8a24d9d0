// The Python module's pieces (pybind11). Each bind_* adds one concept to the module; they call the
// library the CLI calls (pipeline/, latent/, integrators/), never the CLI.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <memory>
#include <string>
#include <vector>

namespace lpt::python {

namespace py = pybind11;

/// A float32 NumPy array that owns `data` (moved, not copied) with the given shape.
py::array_t<float> to_numpy(std::vector<float>&& data, std::vector<py::ssize_t> shape);
/// The array's floats (C order, float32 after conversion). Its shape must be `shape` exactly (a
/// channels-first latent has the right count and would be read as garbage) and its values
/// finite; else a ValueError naming `what`.
std::vector<float> from_numpy(const py::array_t<float, py::array::c_style | py::array::forcecast>& a,
                              const std::vector<py::ssize_t>& shape, const std::string& what);

void bind_scene(py::module_& m);
void bind_latent(py::module_& m);
void bind_pipeline(py::module_& m);

}  // namespace lpt::python
