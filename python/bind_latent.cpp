// latentpt.LatentScene: the latent model of a scene (fresh, or a fit folder's), its parameters as
// arrays, latent renders and the path-replay adjoint that latentpt.torch builds on.
#include "autodiff/fit.h"
#include "autodiff/latent_path_adjoint.h"
#include "autodiff/tone_curve.h"
#include "bindings.h"
#include "pipeline/fit_folder.h"
#include <pybind11/stl.h>
#include <mutex>
#include <optional>

namespace lpt::python {

namespace {

struct LatentScene {
    std::shared_ptr<Scene> scene;
    std::unique_ptr<LatentModel> model;
    ToneCurve tone = ToneCurve::Clip;
    int width = 0, height = 0;  ///< the default latent resolution

    /// Serialises what reads the model (renders, the adjoint, which also writes its gradients)
    /// with what changes it (raw, set_value): either may run in another Python thread, the
    /// renders without the GIL.
    mutable std::mutex busy;

    RenderOptions options(int w, int h, int spp, uint64_t seed) const {
        if (spp <= 0) throw py::value_error("spp must be > 0, got " + std::to_string(spp));
        return RenderOptions::from_scene(*scene, w > 0 ? w : width, h > 0 ? h : height, spp, seed);
    }
    /// A latent image's array shape at `o`: (height, width, 16).
    static std::vector<py::ssize_t> latent_shape(const RenderOptions& o) {
        return {o.height, o.width, kLatentChannels};
    }
    int slice(const std::string& name) const {
        const int i = model->params().find(name);
        if (i < 0) throw py::key_error("no parameter '" + name + "' (LatentScene.slices() lists them)");
        return i;
    }
};

std::shared_ptr<LatentScene> fresh(std::shared_ptr<Scene> scene, const std::string& param, uint64_t seed,
                                   const std::string& terms, const std::string& gate, const std::string& tone,
                                   int width, int height) {
    if (!scene) throw py::type_error("LatentScene: scene must be a latentpt.Scene, got None");
    if (width < 0 || height < 0)
        throw py::value_error("LatentScene: width and height must be >= 0 (0: the scene's), got " +
                              std::to_string(width) + "x" + std::to_string(height));
    auto ls = std::make_shared<LatentScene>();
    ls->scene = std::move(scene);
    ls->model = std::make_unique<LatentModel>(*ls->scene, parameterisation_from_string(param), seed);
    pipeline::configure_terms(*ls->model, gate, terms);
    ls->tone = parse_tone_curve(tone);
    ls->width = width > 0 ? width : ls->scene->camera.width;
    ls->height = height > 0 ? height : ls->scene->camera.height;
    return ls;
}

std::shared_ptr<LatentScene> from_fit(const std::string& dir, const std::map<std::string, std::string>& defines,
                                      const std::string& sampler) {
    const std::optional<SamplerKind> chosen = sampler_choice(sampler);
    pipeline::FitFolder f = [&] {
        py::gil_scoped_release unlocked;  // parsing, meshes, the BVH: other Python threads go on
        return pipeline::load_fit_folder(dir, defines, chosen);
    }();
    auto ls = std::make_shared<LatentScene>();
    ls->scene = std::shared_ptr<Scene>(std::move(f.scene));
    ls->model = std::move(f.model);
    ls->tone = f.tone;
    ls->width = f.latent_width;
    ls->height = f.latent_height;
    return ls;
}

py::list slices(const LatentScene& ls) {
    py::list out;
    const ParamStore& ps = ls.model->params();
    for (size_t i = 0; i < ps.slice_count(); ++i) {
        const ParamSlice& s = ps.slice(int(i));
        py::dict d;
        d["name"] = s.name;
        d["kind"] = s.kind;
        d["map"] = to_string(s.map);
        d["channels"] = s.channels;
        d["raw_offset"] = s.raw_offset;
        d["raw_size"] = s.raw_size();
        out.append(d);
    }
    return out;
}

py::array_t<float> render(const LatentScene& ls, int w, int h, int spp, uint64_t seed, bool linear) {
    const RenderOptions o = ls.options(w, h, spp, seed);
    std::vector<float> img;
    {
        py::gil_scoped_release unlocked;
        const std::lock_guard<std::mutex> lock(ls.busy);
        img = linear ? render_latent_terms<kLatentChannels>(*ls.scene, ls.model->spectra(), ls.model->terms(), o).sum()
                     : render_toned(*ls.model, o, ls.tone);
    }
    return to_numpy(std::move(img), LatentScene::latent_shape(o));
}

/// ∂loss/∂raw for ∂loss/∂(linear latent) of the render with the same options (path replay).
py::array_t<float> backward_linear(LatentScene& ls,
                                   const py::array_t<float, py::array::c_style | py::array::forcecast>& d, int w, int h,
                                   int spp, uint64_t seed) {
    const RenderOptions o = ls.options(w, h, spp, seed);
    const std::vector<float> d_image = from_numpy(d, LatentScene::latent_shape(o), "d_linear");
    ParamStore& ps = ls.model->params();
    std::vector<float> g;
    {
        py::gil_scoped_release unlocked;
        const std::lock_guard<std::mutex> lock(ls.busy);
        ps.zero_grad();
        backward_latent(*ls.model, o, d_image);
        ps.backward();
        g = ps.grad_raw();
    }
    return to_numpy(std::move(g), {py::ssize_t(g.size())});
}

py::array_t<float> tone_forward(const LatentScene& ls,
                                const py::array_t<float, py::array::c_style | py::array::forcecast>& x) {
    std::vector<float> v(x.data(), x.data() + x.size()), out(v.size());
    tone_map(ls.tone, v.data(), out.data(), v.size());
    std::vector<py::ssize_t> shape(x.shape(), x.shape() + x.ndim());
    return to_numpy(std::move(out), shape);
}

py::array_t<float> tone_backward(const LatentScene& ls,
                                 const py::array_t<float, py::array::c_style | py::array::forcecast>& x,
                                 const py::array_t<float, py::array::c_style | py::array::forcecast>& d) {
    const std::vector<float> v(x.data(), x.data() + x.size());
    const std::vector<float> dv = from_numpy(d, std::vector<py::ssize_t>(x.shape(), x.shape() + x.ndim()), "d_toned");
    std::vector<float> out(v.size());
    tone_map_backward(ls.tone, v.data(), dv.data(), out.data(), v.size());
    std::vector<py::ssize_t> shape(x.shape(), x.shape() + x.ndim());
    return to_numpy(std::move(out), shape);
}

void set_raw(LatentScene& ls, const py::array_t<float, py::array::c_style | py::array::forcecast>& raw) {
    ParamStore& ps = ls.model->params();
    std::vector<float> r = from_numpy(raw, {py::ssize_t(ps.raw().size())}, "raw");
    // What params.json refuses too (a log-gain that would overflow e^g, docs/params.md (4)).
    for (size_t i = 0; i < ps.slice_count(); ++i) {
        const ParamSlice& s = ps.slice(int(i));
        for (size_t k = 0; k < s.raw_size(); ++k) {
            const std::string problem = s.raw_problem(k, r[s.raw_offset + k]);
            if (!problem.empty()) throw py::value_error("raw: " + s.name + ": " + problem);
        }
    }
    py::gil_scoped_release unlocked;  // while a render in another thread finishes
    const std::lock_guard<std::mutex> lock(ls.busy);
    ps.raw() = std::move(r);
    ls.model->sync();
}

py::array_t<float> value_of(const LatentScene& ls, const std::string& name) {
    const int i = ls.slice(name);
    std::vector<float> out;
    {
        // a set_value or raw write in another thread must not be read half done (1747 torn reads
        // in 902k unguarded)
        py::gil_scoped_release unlocked;
        const std::lock_guard<std::mutex> lock(ls.busy);
        const float* v = ls.model->params().value(i);
        out.assign(v, v + ls.model->params().slice(i).channels);
    }
    return to_numpy(std::move(out), {py::ssize_t(out.size())});
}

py::array_t<float> raw_of(const LatentScene& ls) {
    std::vector<float> r;
    {
        py::gil_scoped_release unlocked;
        const std::lock_guard<std::mutex> lock(ls.busy);
        r = ls.model->params().raw();
    }
    return to_numpy(std::move(r), {py::ssize_t(r.size())});
}

void set_value(LatentScene& ls, const std::string& name,
               const py::array_t<float, py::array::c_style | py::array::forcecast>& v) {
    const int i = ls.slice(name);
    const std::vector<float> values = from_numpy(v, {py::ssize_t(ls.model->params().slice(i).channels)}, name);
    py::gil_scoped_release unlocked;
    const std::lock_guard<std::mutex> lock(ls.busy);
    ls.model->params().set_value(i, values.data());
    ls.model->sync();
}

}  // namespace

void bind_latent(py::module_& m) {
    py::class_<LatentScene, std::shared_ptr<LatentScene>>(
        m, "LatentScene",
        "The learnable latent model of a scene: per-shape 16-channel parameters, latent renders, gradients.")
        .def(py::init(&fresh), py::arg("scene"), py::arg("param") = "code", py::arg("seed") = 0,
             py::arg("terms") = "eac", py::arg("gate") = "shadowed", py::arg("tone") = "clip", py::arg("width") = 0,
             py::arg("height") = 0, "A fresh model of `scene`, parameters initialised from `seed` (docs/params.md).")
        .def_static("from_fit", &from_fit, py::arg("fitdir"), py::arg("defines") = std::map<std::string, std::string>{},
                    py::arg("sampler") = "",
                    "The fitted model of a fit folder written by `latentpt fit` or latentpt.fit(); `sampler` "
                    "replaces the fit's.")
        .def_property_readonly("width", [](const LatentScene& l) { return l.width; })
        .def_property_readonly("height", [](const LatentScene& l) { return l.height; })
        .def_property_readonly("scene", [](const LatentScene& l) { return l.scene; })
        .def("slices", &slices, "Every parameter slice: name, kind, map, channels, raw_offset, raw_size.")
        .def_property("raw", &raw_of, &set_raw,
                      "All raw (optimiser-side) parameters as one flat array; setting it updates the model.")
        .def("value", &value_of, py::arg("name"), "A slice's value (its map applied to its raw parameters).")
        .def("set_value", &set_value, py::arg("name"), py::arg("value"),
             "Sets a slice's raw parameters so that its value is `value`.")
        .def(
            "render",
            [](const LatentScene& l, int w, int h, int spp, uint64_t seed) {
                return render(l, w, h, spp, seed, false);
            },
            py::arg("width") = 0, py::arg("height") = 0, py::arg("spp") = 64, py::arg("seed") = 0,
            "The tone-mapped latent (what the VAE reads), (height, width, 16).")
        .def(
            "render_linear",
            [](const LatentScene& l, int w, int h, int spp, uint64_t seed) { return render(l, w, h, spp, seed, true); },
            py::arg("width") = 0, py::arg("height") = 0, py::arg("spp") = 64, py::arg("seed") = 0,
            "Ĩe + Ĩa + Ĩc before the tone curve, (height, width, 16).")
        .def("tone", &tone_forward, py::arg("linear"), "The model's signed tone curve applied to a linear latent.")
        .def("tone_backward", &tone_backward, py::arg("linear"), py::arg("d_toned"), "∂loss/∂linear from ∂loss/∂toned.")
        .def("backward_linear", &backward_linear, py::arg("d_linear"), py::arg("width") = 0, py::arg("height") = 0,
             py::arg("spp") = 64, py::arg("seed") = 0,
             "∂loss/∂raw (flat, as `raw`) for ∂loss/∂(linear latent) of render_linear with the same arguments: path "
             "replay backpropagation.");
}

}  // namespace lpt::python
