// `import latentpt`: the native part (_latentpt). python/latentpt/__init__.py re-exports it and
// latentpt/torch.py adds the autograd function. docs/python.md.
#include "bindings.h"
#include "core/error.h"
#include "pipeline/progress.h"

namespace lpt::python {

py::array_t<float> to_numpy(std::vector<float>&& data, std::vector<py::ssize_t> shape) {
    auto* owned = new std::vector<float>(std::move(data));
    py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>(shape, owned->data(), free_when_done);
}

std::vector<float> from_numpy(const py::array_t<float, py::array::c_style | py::array::forcecast>& a, size_t expected,
                              const char* what) {
    if (size_t(a.size()) != expected)
        throw py::value_error(std::string(what) + ": expected " + std::to_string(expected) + " floats, got " +
                              std::to_string(a.size()));
    return std::vector<float>(a.data(), a.data() + a.size());
}

}  // namespace lpt::python

PYBIND11_MODULE(_latentpt, m) {
    namespace py = pybind11;
    m.doc() = "latentpt: a differentiable path tracer that renders into the latent space of an image autoencoder";
    py::register_exception<lpt::SceneError>(m, "SceneError", PyExc_ValueError);
    py::register_exception<lpt::pipeline::Cancelled>(m, "Cancelled", PyExc_RuntimeError);
    lpt::python::bind_scene(m);
    lpt::python::bind_latent(m);
    lpt::python::bind_pipeline(m);
}
