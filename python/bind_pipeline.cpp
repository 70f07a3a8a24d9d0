// latentpt.fit / refine / render_edits and latentpt.Vae: the pipeline library with Python
// progress callbacks (returning False cancels: latentpt.Cancelled is raised) and the VAE on arrays.
#include "bindings.h"
#include "pipeline/edit.h"
#include "pipeline/edit_session.h"
#include "pipeline/fit_folder.h"
#include "pipeline/fit.h"
#include "pipeline/refine.h"
#include "pipeline/vae_source.h"
#include "vae/vae.h"
#include <algorithm>
#include <set>
#include <pybind11/stl.h>

namespace lpt::python {

namespace {

/// Calls `progress(dict)` after every step (a falsy return cancels) and `note(str)` for notes;
/// without a note callback notes go to Python's stderr. The pipeline runs without the GIL (torch's
/// autograd refuses to run while it is held, and other Python threads go on), so each callback
/// takes it back; they hold borrowed handles, kept alive by the caller's arguments for the call.
pipeline::Reporter reporter(const py::object& progress_object, const py::object& note_object) {
    pipeline::Reporter r;
    const py::handle progress = progress_object, note = note_object;
    if (!progress.is_none())
        r.progress = [progress](const pipeline::StageProgress& p) {
            py::gil_scoped_acquire gil;
            py::dict d;
            d["stage"] = p.stage;
            d["step"] = p.step;
            d["total"] = p.total;
            d["start"] = p.start;
            d["seconds"] = p.seconds;
            d["status"] = p.status;
            const py::object keep = progress(d);
            if (!keep.is_none() && !py::isinstance<py::bool_>(keep))  // "stop" was a cast error's text
                throw py::type_error("progress callback must return True, False (cancel) or None, got " +
                                     std::string(py::str(keep.get_type().attr("__name__"))));
            return keep.is_none() || keep.cast<bool>();
        };
    r.note = [note](const std::string& text) {
        py::gil_scoped_acquire gil;
        if (note.is_none()) py::print(text, py::arg("file") = py::module_::import("sys").attr("stderr"));
        else note(text);
    };
    return r;
}

/// f() with the GIL released: the pipeline's long calls (see reporter()).
template <class F>
auto without_gil(F&& f) {
    py::gil_scoped_release unlocked;
    return f();
}

/// A string option that takes one of two words, as the CLI's: true for `yes`.
bool either(const std::string& option, const std::string& v, const char* yes, const char* no) {
    if (v != yes && v != no) throw py::value_error(option + " must be '" + yes + "' or '" + no + "', got '" + v + "'");
    return v == yes;
}

/// Sets the RefineJob field that `key` names (refine --<key> with underscores, e.g. lr_decay);
/// false when the key is not a refiner option. Ranges are checked by pipeline::validate; errors
/// name the option as the caller spelled it (`prefix` + key: fit's refiner_norm).
bool apply_refine_option(pipeline::RefineJob& job, const std::string& k, const py::handle& value,
                         const std::string& prefix = "") {
    const std::string shown = prefix + k;
    RefinerTrainOptions& t = job.train;
    RefinerConfig& n = job.net;
    if (k == "iterations") t.iterations = value.cast<int>();
    else if (k == "expansion") n.expansion = value.cast<int>();
    else if (k == "crop") t.crop = value.cast<int>();
    else if (k == "lpips_crop") t.lpips_crop = value.cast<int>();
    else if (k == "lr") t.lr = value.cast<float>();
    else if (k == "lr_decay") t.cosine_decay = either(shown, value.cast<std::string>(), "cosine", "none");
    else if (k == "patience") t.patience = value.cast<int>();
    else if (k == "w_mse") t.w_mse = value.cast<float>();
    else if (k == "w_ssim") t.w_ssim = value.cast<float>();
    else if (k == "w_lpips") t.w_lpips = value.cast<float>();
    else if (k == "squash") n.squash = value.cast<float>();
    else if (k == "arch") n.arch = parse_refiner_arch(value.cast<std::string>(), shown);
    else if (k == "inputs") n.terms = either(shown, value.cast<std::string>(), "terms", "latent");
    else if (k == "emitter_cells") n.emitter_cells = value.cast<int>();
    else if (k == "norm") n.instance_norm = either(shown, value.cast<std::string>(), "instance", "none");
    else if (k == "inference") job.windowed_inference = either(shown, value.cast<std::string>(), "windows", "whole");
    else if (k == "window_stride") job.window_stride = value.cast<int>();
    else if (k == "dropout") n.dropout = value.cast<float>();
    else if (k == "noise_views") job.noise_views = value.cast<int>();
    else if (k == "input_noise") t.input_noise = value.cast<float>();
    else if (k == "augment") job.augment = pipeline::parse_refiner_augment(value.cast<std::string>());
    else if (k == "latent_target")
        job.compensated_target = either(shown, value.cast<std::string>(), "compensated", "encoded");
    else if (k == "latent_target_block") job.latent_target_block = value.cast<int>();
    else if (k == "checkpoint_every") t.checkpoint_every = value.cast<int>();
    else if (k == "lpips_dir") job.lpips_dir = value.cast<std::string>();
    else if (k == "sampler" && prefix.empty()) job.sampler = sampler_choice(value.cast<std::string>(), shown);
    else if (k == "seed") t.seed = value.cast<uint64_t>();
    else if (k == "restart_if_changed") job.restart_if_changed = value.cast<bool>();
    else if (k == "emitters" && prefix.empty()) job.emitters = value.cast<bool>();
    else return false;
    return true;
}

/// Sets the FitJob field that `k` names (fit --<k> with underscores); false when there is none.
bool apply_fit_option(pipeline::FitJob& job, const std::string& k, const py::handle& value) {
    FitOptions& o = job.options;
    if (k == "iterations") o.iterations = value.cast<int>();
    else if (k == "spp") o.spp = value.cast<int>();
    else if (k == "seed") o.seed = value.cast<uint64_t>();
    else if (k == "lr") o.lr = value.cast<float>();
    else if (k == "lr_min") o.lr_min = value.cast<float>();
    else if (k == "lr_period") o.lr_period = value.cast<int>();
    else if (k == "patience") o.patience = value.cast<int>();
    else if (k == "emission_decay") o.emission_decay = value.cast<float>();
    else if (k == "emitter_response_decay") o.emitter_response_decay = value.cast<float>();
    else if (k == "exposures") o.exposures = value.cast<std::vector<float>>();
    else if (k == "reuse_paths") o.reuse_paths = value.cast<int>();
    else if (k == "checkpoint_every") o.checkpoint_every = value.cast<int>();
    else if (k == "tone") o.tone = parse_tone_curve(value.cast<std::string>());
    else if (k == "final_spp") job.final_spp = value.cast<int>();
    else if (k == "target") job.target = value.cast<std::string>();
    else if (k == "encode") job.encode = value.cast<bool>();
    else if (k == "encode_res") job.encode_res = value.cast<std::string>();
    else if (k == "ref_spp") job.ref_spp = value.cast<int>();
    else if (k == "synthetic_res") job.synthetic_res = value.cast<std::string>();
    else if (k == "param") job.param = value.cast<std::string>();
    else if (k == "gate") job.gate = value.cast<std::string>();
    else if (k == "terms") job.terms = value.cast<std::string>();
    else if (k == "resume") job.resume = value.cast<bool>();
    else if (k == "restart_if_changed") job.restart_if_changed = value.cast<bool>();
    else if (k == "refiner") job.refiner = value.cast<bool>();
    else if (k == "sampler") job.sampler = sampler_choice(value.cast<std::string>(), k);
    else if (k == "vae_dir") job.vae.dir = value.cast<std::string>();
    else if (k == "lpips_dir") job.refine.lpips_dir = value.cast<std::string>();  // fit --lpips-dir
    else if (k.rfind("refiner_", 0) == 0 && k != "refiner_seed")
        return apply_refine_option(job.refine, k.substr(8), value, "refiner_");
    else return false;
    return true;
}

/// Applies `options` through `apply` (true: the option exists), each a TypeError naming it
/// when its value is of the wrong type or it is unknown to `call`.
template <typename Apply>
void apply_options(const char* call, const py::dict& options, Apply apply) {
    static const std::set<std::string> flags = {"encode", "resume", "restart_if_changed", "refiner", "emitters"};
    for (const auto& [key, value] : options) {
        const std::string k = py::str(key);
        const std::string type = py::str(value.get_type().attr("__name__"));
        // True is an int to pybind11: iterations=True ran one iteration
        if (py::isinstance<py::bool_>(value) && !flags.count(k))
            throw py::type_error(std::string(call) + "(): option '" + k + "' cannot be a bool");
        bool known = false;
        try {
            known = apply(k, value);
        } catch (const py::cast_error&) {
            // seed=-1 said "cannot be a int": an int the option takes (0 casts) failed on its range
            bool takes_ints = false;
            if (py::isinstance<py::int_>(value)) try {
                    takes_ints = apply(k, py::int_(0));  // the job is thrown away with the error below
                } catch (const py::cast_error&) {}
            if (takes_ints)
                throw py::value_error(
                    std::string(call) + "(): option '" + k + "' = " + std::string(py::str(value)) +
                    " is out of its range" +
                    (k.find("seed") != std::string::npos ? " (0 to 2^64 - 1)" : " (a 32-bit integer)"));
            throw py::type_error(std::string(call) + "(): option '" + k + "' cannot be a " + type);
        }
        if (!known) throw py::type_error(std::string(call) + "() got an unknown option '" + k + "'");
    }
}

/// Sets the job fields named in `options` (the CLI's option names with underscores).
void apply_fit_options(pipeline::FitJob& job, const py::dict& options) {
    apply_options("fit", options,
                  [&](const std::string& k, const py::handle& v) { return apply_fit_option(job, k, v); });
}

py::dict run_fit(const std::string& scene, const std::string& out, const std::map<std::string, std::string>& defines,
                 const py::object& progress, const py::object& note, const py::kwargs& options) {
    pipeline::FitJob job;
    job.scene = scene;
    job.out = out;
    job.defines = defines;
    apply_fit_options(job, options);
    // what the CLI refuses as doing nothing alone (docs/reliability.md)
    // by value, not by presence: a wrapper that passes every option at its default is fine
    const pipeline::FitJob defaults;
    if (!job.encode && (job.encode_res != defaults.encode_res || job.ref_spp != defaults.ref_spp))
        throw py::value_error(std::string("fit(): option '") +
                              (job.encode_res != defaults.encode_res ? "encode_res" : "ref_spp") +
                              "' needs encode=True");
    if (job.restart_if_changed && !job.resume)
        throw py::value_error("fit(): option 'restart_if_changed' needs resume=True");
    pipeline::validate(job);
    const pipeline::Reporter report = reporter(progress, note);
    const pipeline::FitSummary s = without_gil([&] { return pipeline::run_fit(job, report); });
    py::dict d;
    d["latent_width"] = s.latent_width;
    d["latent_height"] = s.latent_height;
    d["final_loss"] = s.final_loss;
    d["iterations_run"] = s.state.next_iteration;
    d["best_iteration"] = s.state.best_iteration;
    if (s.refined) d["metrics"] = py::module_::import("json").attr("loads")(s.refined->metrics.dump());
    return d;
}

py::dict run_refine(const std::string& fitdir, bool resume, const py::object& progress, const py::object& note,
                    const py::kwargs& options) {
    pipeline::RefineJob job;
    job.fitdir = fitdir;
    job.resume = resume;
    apply_options("refine", options,
                  [&](const std::string& k, const py::handle& v) { return apply_refine_option(job, k, v); });
    const pipeline::Reporter report = reporter(progress, note);
    const pipeline::RefineSummary s = without_gil([&] { return pipeline::run_refine(job, report); });
    return py::module_::import("json").attr("loads")(s.metrics.dump());
}

int render_edits(const std::string& fitdir, const std::string& edits, const std::string& out, int spp, uint64_t seed,
                 bool reference, const std::string& sampler, const py::object& progress, const py::object& note) {
    pipeline::EditJob job;
    job.sampler = sampler_choice(sampler);
    job.fitdir = fitdir;
    job.edits = edits;
    job.out = out;
    job.spp = spp;
    job.seed = seed;
    job.reference = reference;
    const pipeline::Reporter report = reporter(progress, note);
    return without_gil([&] { return pipeline::render_edits(job, report); });
}

struct PyVae {
    std::shared_ptr<Vae> vae;
};

py::array_t<float> encode(const PyVae& v, const py::array_t<float, py::array::c_style | py::array::forcecast>& rgb) {
    if (rgb.ndim() != 3 || rgb.shape(2) != 3) throw py::value_error("encode: expected an (height, width, 3) array");
    const int h = int(rgb.shape(0)), w = int(rgb.shape(1)), f = v.vae->convention().downsample;
    if (h < f || w < f)  // torch's own error here is a C++ stack trace
        throw py::value_error("encode: the image must be at least " + std::to_string(f) + "x" + std::to_string(f) +
                              ", got " + std::to_string(w) + "x" + std::to_string(h));
    std::vector<float> in = from_numpy(rgb, {h, w, 3}, "encode: rgb"), out;
    // Display values: 0-255 bytes read as floats gave latents of +-700 without a word. A decoded
    // image (not clamped, about [-0.1, 1.2]) must still go back in.
    const auto [lo, hi] = std::minmax_element(in.begin(), in.end());
    if (*lo < -0.5f || *hi > 1.5f)
        throw py::value_error("encode: rgb must be display values, about [0, 1], got [" + std::to_string(*lo) + ", " +
                              std::to_string(*hi) + "] (8-bit images: divide by 255)");
    {
        py::gil_scoped_release unlocked;
        out = v.vae->encode(in, w, h);
    }
    return to_numpy(std::move(out), {h / f, w / f, v.vae->convention().channels});
}

py::array_t<float> decode(const PyVae& v, const py::array_t<float, py::array::c_style | py::array::forcecast>& latent) {
    if (latent.ndim() != 3 || latent.shape(2) != v.vae->convention().channels)
        throw py::value_error("decode: expected a (height, width, " + std::to_string(v.vae->convention().channels) +
                              ") array");
    const int h = int(latent.shape(0)), w = int(latent.shape(1)), f = v.vae->convention().downsample;
    if (h < 1 || w < 1) throw py::value_error("decode: the latent is empty");
    std::vector<float> in = from_numpy(latent, {h, w, v.vae->convention().channels}, "decode: latent"), out;
    {
        py::gil_scoped_release unlocked;
        out = v.vae->decode(in, w, h);
    }
    return to_numpy(std::move(out), {h * f, w * f, 3});
}

py::dict edited_frame(pipeline::EditSession& s, int i, int spp, uint64_t seed, int width, int height) {
    pipeline::FrameLatents f;
    {
        py::gil_scoped_release unlocked;
        f = s.frame(i, spp, seed, width, height);
    }
    py::dict d;
    d["latent"] = to_numpy(std::move(f.latent), {f.height, f.width, 16});
    d["refined"] = f.refined.empty() ? py::object(py::none())
                                     : py::object(to_numpy(std::move(f.refined), {f.height, f.width, 16}));
    return d;
}

}  // namespace

void bind_pipeline(py::module_& m) {
    m.def(
        "fit", &run_fit, py::arg("scene"), py::arg("out"), py::arg("defines") = std::map<std::string, std::string>{},
        py::arg("progress") = py::none(), py::arg("note") = py::none(),
        "Stage 1 (and stage 2 unless refiner=False) into the fit folder `out`; keyword options as the CLI's "
        "(iterations, spp, seed, lr, encode, encode_res, synthetic_res, param, gate, terms, refiner_iterations, ...).");
    m.def("refine", &run_refine, py::arg("fitdir"), py::arg("resume") = false, py::arg("progress") = py::none(),
          py::arg("note") = py::none(),
          "Stage 2 on a fit folder; returns metrics.json. Keyword options as `latentpt refine`'s with underscores "
          "(iterations, lr, lr_decay, crop, patience, augment, noise_views, input_noise, latent_target, norm, arch, "
          "inputs, inference, dropout, seed, emitters, ...).");
    m.def("render_edits", &render_edits, py::arg("fitdir"), py::arg("edits"), py::arg("out"), py::arg("spp") = 64,
          py::arg("seed") = 0, py::arg("reference") = false, py::arg("sampler") = "", py::arg("progress") = py::none(),
          py::arg("note") = py::none(),
          "A fit's edit sequence (edits.json, as `render --edit`); returns the number of frames. `sampler` "
          "replaces the fit's.");
    py::class_<PyVae>(m, "Vae", "An image autoencoder: TAESD3 weights in a folder (default ../shared/models/taesd3).")
        .def(py::init([](const std::string& dir) {
                 py::gil_scoped_release unlocked;  // loading weights: other Python threads go on
                 return PyVae{std::shared_ptr<Vae>(pipeline::open_vae({dir, "", "", ""}))};
             }),
             py::arg("dir") = "")
        .def_static(
            "from_fit",
            [](const std::string& fitdir) {
                py::gil_scoped_release unlocked;
                return PyVae{std::shared_ptr<Vae>(pipeline::open_vae(pipeline::manifest_vae(fitdir + "/fit.json")))};
            },
            py::arg("fitdir"), "The VAE a fit folder was fitted with (its fit.json).")
        .def("encode", &encode, py::arg("rgb"), "Display RGB in [0, 1], (H, W, 3) -> latent (H/8, W/8, 16).")
        .def("decode", &decode, py::arg("latent"), "Latent (h, w, 16) -> display RGB (8h, 8w, 3).");
    py::class_<pipeline::EditSession>(m, "EditSession",
                                      "A fit's edit sequence (the JSON of render --edit), frame by frame as arrays.")
        .def(py::init([](const std::string& fitdir, const std::string& edits,
                         const std::map<std::string, std::string>& defines, const std::string& sampler) {
                 return std::make_unique<pipeline::EditSession>(fitdir, edits, defines, sampler_choice(sampler));
             }),
             py::arg("fitdir"), py::arg("edits"), py::arg("defines") = std::map<std::string, std::string>{},
             py::arg("sampler") = "")
        .def_property_readonly("frames", &pipeline::EditSession::frames)
        .def_property_readonly("has_refiner", &pipeline::EditSession::has_refiner)
        .def("frame", &edited_frame, py::arg("i"), py::arg("spp") = 64, py::arg("seed") = 0, py::arg("width") = 0,
             py::arg("height") = 0,
             "Frame i as render --edit makes it: {'latent': (h, w, 16), 'refined': (h, w, 16) or None}.");
}

}  // namespace lpt::python
