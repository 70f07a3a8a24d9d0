// latentpt.Scene: a scene file loaded (JSON or Mitsuba XML, -D overrides), rendered in RGB and AOVs.
#include "bindings.h"
#include "core/scene_loader.h"
#include "integrators/aov.h"
#include "integrators/path.h"
#include <pybind11/stl.h>

namespace lpt::python {

namespace {

/// Negative sizes rendered the scene's size without a word.
void require_size(int width, int height) {
    if (width < 0 || height < 0)
        throw py::value_error("width and height must be >= 0 (0: the scene's), got " + std::to_string(width) + "x" +
                              std::to_string(height));
}

RenderOptions options_for(const Scene& scene, int spp, int width, int height, uint64_t seed, int max_depth) {
    if (spp < 0) throw py::value_error("spp must be > 0, or 0 for the scene's own; got " + std::to_string(spp));
    require_size(width, height);
    if (max_depth < -2)  // -1 unbounded as in scene files, -2 the scene's
        throw py::value_error("max_depth must be >= -1 (-1: unbounded), got " + std::to_string(max_depth));
    RenderOptions o = RenderOptions::from_scene(scene);
    if (spp > 0) o.spp = spp;
    o.width = width;
    o.height = height;
    o.seed = seed;
    if (max_depth != -2) o.max_depth = max_depth;
    return o;
}

py::array_t<float> render_rgb(const Scene& scene, int spp, int width, int height, uint64_t seed, int max_depth) {
    const RenderOptions o = options_for(scene, spp, width, height, seed, max_depth);
    std::vector<float> rgb;
    {
        py::gil_scoped_release unlocked;
        rgb = render_path<3>(scene, SceneSpectra<3>::from_description(scene), o).develop();
    }
    const int w = width > 0 ? width : scene.camera.width, h = height > 0 ? height : scene.camera.height;
    return to_numpy(std::move(rgb), {h, w, 3});
}

py::dict render_aov_images(const Scene& scene, int width, int height, int spp, uint64_t seed) {
    if (spp <= 0) throw py::value_error("spp must be > 0, got " + std::to_string(spp));
    require_size(width, height);
    AovImages a;
    {
        py::gil_scoped_release unlocked;
        a = render_aovs(scene, SceneSpectra<3>::from_description(scene), width > 0 ? width : scene.camera.width,
                        height > 0 ? height : scene.camera.height, spp, seed, scene.integrator.sampler);
    }
    py::dict d;
    d["normal"] = to_numpy(std::move(a.normal), {a.height, a.width, 3});
    d["distance"] = to_numpy(std::move(a.distance), {a.height, a.width});
    d["albedo"] = to_numpy(std::move(a.albedo), {a.height, a.width, 3});
    return d;
}

}  // namespace

void bind_scene(py::module_& m) {
    py::class_<Scene, std::shared_ptr<Scene>>(m, "Scene",
                                              "A scene file (.json or Mitsuba 3 .xml) loaded for rendering.")
        .def(py::init([](const std::string& path, const std::map<std::string, std::string>& defines,
                         const std::string& sampler) {
                 const std::optional<SamplerKind> chosen = sampler_choice(sampler);
                 py::gil_scoped_release unlocked;  // parsing, meshes, the BVH: other Python threads go on
                 return std::make_shared<Scene>(load_scene(path, defines, chosen));
             }),
             py::arg("path"), py::arg("defines") = std::map<std::string, std::string>{}, py::arg("sampler") = "",
             "Loads a scene; `defines` override values as -D does on the command line, `sampler` ('sobol' or "
             "'independent') the file's as --sampler does.")
        .def_property(
            "sampler", [](const Scene& s) { return std::string(sampler_name(s.integrator.sampler)); },
            [](Scene& s, const std::string& name) { s.integrator.sampler = sampler_named(name); },
            "'sobol' or 'independent': the random numbers of every render of this scene (docs/sampling.md).")
        .def_property_readonly("width", [](const Scene& s) { return s.camera.width; })
        .def_property_readonly("height", [](const Scene& s) { return s.camera.height; })
        .def_property_readonly("spp", [](const Scene& s) { return s.integrator.spp; })
        .def_property_readonly("file", [](const Scene& s) { return s.file; })
        .def("shape_ids",
             [](const Scene& s) {
                 std::vector<std::string> ids;
                 for (const Shape& shape : s.shapes) ids.push_back(shape.id);
                 return ids;
             })
        .def("render", &render_rgb, py::arg("spp") = 0, py::arg("width") = 0, py::arg("height") = 0,
             py::arg("seed") = 0, py::arg("max_depth") = -2,
             "Path-traced linear RGB as a (height, width, 3) float32 array; 0 = the scene's value, max_depth -2 = "
             "the scene's.")
        .def("aovs", &render_aov_images, py::arg("width") = 0, py::arg("height") = 0, py::arg("spp") = 4,
             py::arg("seed") = 0, "Normal, distance and albedo AOVs as a dict of arrays.");
}

}  // namespace lpt::python
