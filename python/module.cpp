// `import latentpt`: the native part (_latentpt). python/latentpt/__init__.py re-exports it and
// latentpt/torch.py adds the autograd function. docs/python.md.
#include "bindings.h"
#include "autodiff/loss.h"
#include "core/error.h"
#include "pipeline/progress.h"
#include <string>

namespace lpt::python {

py::array_t<float> to_numpy(std::vector<float>&& data, std::vector<py::ssize_t> shape) {
    auto* owned = new std::vector<float>(std::move(data));
    py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<float>*>(p); });
    return py::array_t<float>(shape, owned->data(), free_when_done);
}

namespace {
std::string shape_text(const std::vector<py::ssize_t>& shape) {
    std::string text = "(";
    for (size_t i = 0; i < shape.size(); ++i) text += (i ? ", " : "") + std::to_string(shape[i]);
    return text + (shape.size() == 1 ? ",)" : ")");
}
}  // namespace

std::vector<float> from_numpy(const py::array_t<float, py::array::c_style | py::array::forcecast>& a,
                              const std::vector<py::ssize_t>& shape, const std::string& what) {
    const std::vector<py::ssize_t> got(a.shape(), a.shape() + a.ndim());
    if (got != shape)
        throw py::value_error(what + ": expected an array of shape " + shape_text(shape) + ", got " + shape_text(got));
    std::vector<float> v(a.data(), a.data() + a.size());
    size_t bad = 0;
    if (check_finite(v.data(), v.size(), &bad)) return v;
    std::vector<py::ssize_t> at(shape.size());  // the flat index as the caller's (i, j, k)
    for (size_t d = shape.size(); d-- > 0; bad /= size_t(shape[d])) at[d] = py::ssize_t(bad % size_t(shape[d]));
    throw py::value_error(what + ": the value at " + shape_text(at) + " is not finite (as a float32)");
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
