#include "pipeline/fit.h"
#include "autodiff/loss.h"
#include "core/image_io.h"
#include "core/latent_viz.h"
#include "core/scene_loader.h"
#include "pipeline/emitter_refiner.h"
#include "pipeline/fit_checkpoint.h"
#include "pipeline/fit_folder.h"
#include "pipeline/output_lock.h"
#include "pipeline/reference.h"
#include "pipeline/refiner_io.h"
#include "pipeline/resolution.h"
#include "vae/vae.h"
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <optional>
#include <sstream>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

struct Target {
    std::vector<float> data;
    int width = 0, height = 0;  ///< latent resolution
    /// The training view with every light k times as bright, encoded, for each k ≠ 1 of
    /// --exposures (docs/fitting.md "Exposure cycle").
    std::vector<ExposureTarget> exposed;
};

Target load_target_exr(const std::string& path) {
    Image img = read_image(path);
    if (img.channels != kLatentChannels)
        throw std::runtime_error(path + ": target has " + std::to_string(img.channels) +
                                 " channels, a latent map needs " + std::to_string(kLatentChannels) +
                                 " (an RGB image needs --encode)");
    require_finite_pixels(img, path);
    return {img.data, img.width, img.height};
}

/// The paper's target: path-traced RGB, display-mapped, encoded by the VAE. The RGB is kept as
/// reference_rgb.exr: the refiner's LPIPS and metrics.json compare decoded latents with it.
Target encoded_target(const FitJob& job, const Scene& scene, const Vae& vae, const Reporter& report) {
    int iw = 0, ih = 0;
    parse_resolution(job.encode_res, iw, ih, "--encode-res");
    const fs::path out(job.out);
    std::vector<float> ref_rgb, linear;
    Target t;
    std::string cached;
    if (!job.reference_cache.empty())
        cached = (fs::path(job.reference_cache) / training_reference_key(iw, ih, job.ref_spp, job.ref_tone)).string();
    const std::vector<float> exposures = exposures_other_than_1(job.options.exposures);
    t.data = cached_encoded_reference(scene, iw, ih, job.ref_spp, kReferenceSeed, job.ref_tone, vae, cached,
                                      reference_source(scene, job.defines), vae_encoder_fingerprint(job.vae),
                                      (out / "reference.png").string(), ref_rgb, report,
                                      exposures.empty() ? nullptr : &linear);
    write_exr((out / "reference_rgb.exr").string(), Image{iw, ih, 3, ref_rgb, {"R", "G", "B"}, true});
    t.width = iw / 8;
    t.height = ih / 8;
    for (float k : exposures) {
        // k·I display-mapped: a light's own pixels stay clipped, the room's light scales
        std::vector<float> rgb(linear.size());
        for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = display_value(k * linear[i], job.ref_tone);
        t.exposed.push_back({k, vae.encode(rgb, iw, ih)});
    }
    return t;
}

/// A target the latent renderer makes itself from random parameters: for trying the fit without
/// a VAE, and the test suite's convergence check.
Target synthetic_target(const FitJob& job, const Scene& scene) {
    Target t;
    parse_resolution(job.synthetic_res, t.width, t.height, "--synthetic-res");
    LatentModel truth(scene, parameterisation_from_string(job.param), job.synthetic_seed);
    RenderOptions ro = RenderOptions::from_scene(scene, t.width, t.height, job.final_spp, job.synthetic_seed);
    t.data = render_toned(truth, ro, job.options.tone);
    return t;
}

std::string loss_csv(const FitState& st) {
    std::ostringstream out;
    out << "iteration,loss,smoothed_loss,lr,seconds\n";
    for (const FitRecord& r : st.history)
        out << r.iteration << "," << r.loss << "," << r.smoothed << "," << r.lr << "," << r.seconds << "\n";
    return out.str();
}

std::string fit_status(const FitRecord& r) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "loss %.5f (smoothed %.5f) | lr %.2e", r.loss, r.smoothed, r.lr);
    return buf;
}

/// Runs the optimiser from `state`, reporting every iteration; false when the reporter cancelled.
bool optimise(LatentModel& model, const Target& target, const FitOptions& o, FitState& state, const Reporter& report) {
    const int start = state.next_iteration;
    const double seconds_at_start = state.history.empty() ? 0.0 : state.history.back().seconds;
    bool cancelled = false;
    std::set<std::string> reported;  // once per parameter; the summary counts every refused step
    auto on_iteration = [&](const FitRecord& r, const FitState&) {
        if (r.refused && reported.insert(r.refused_parameter).second)
            report.say("warning: iteration " + std::to_string(r.iteration) + ": the gradient of '" +
                       r.refused_parameter + "' is not finite: step refused, parameters and Adam state kept");
        StageProgress p;
        p.stage = "fit";
        p.step = r.iteration + 1;
        p.total = o.iterations;
        p.start = start;
        p.seconds = r.seconds - seconds_at_start;
        p.status = fit_status(r);
        cancelled = !report.step(p);
        return !cancelled;
    };
    std::vector<ExposureTarget> targets = target.exposed;
    targets.push_back({1.f, target.data});
    state = fit_latent(model, targets, target.width, target.height, o, state, on_iteration);
    return !cancelled;
}

void write_latent_pictures(const fs::path& out, const Target& target, const std::vector<float>& toned) {
    const int w = target.width, h = target.height;
    std::vector<float> diff(toned.size());
    for (size_t i = 0; i < toned.size(); ++i) diff[i] = toned[i] - target.data[i];
    float scale = 0.f;
    for (float v : target.data) scale = std::max(scale, std::abs(v));
    write_png_srgb((out / "target.png").string(), latent_grid(target.data.data(), w, h, kLatentChannels, scale));
    write_png_srgb((out / "render.png").string(), latent_grid(toned.data(), w, h, kLatentChannels, scale));
    write_png_srgb((out / "diff.png").string(), latent_grid(diff.data(), w, h, kLatentChannels, scale));
}

/// What a person looks at: the fitted latent decoded to RGB next to the decoded target.
void write_decoded(const fs::path& out, const Vae& vae, const Target& target, const std::vector<float>& toned) {
    const int f = vae.convention().downsample, w = target.width, h = target.height;
    write_png_display((out / "decoded.png").string(), Image{w * f, h * f, 3, vae.decode(toned, w, h), {"R", "G", "B"}});
    write_png_display((out / "target_decoded.png").string(),
                      Image{w * f, h * f, 3, vae.decode(target.data, w, h), {"R", "G", "B"}});
}

/// The final render of the best parameters at final_spp and everything stage 2 and `render
/// --edit` read: params.json, fit.json, latent*.exr, aov.exr, loss.csv, pictures.
double write_stage1(const FitJob& job, const LatentModel& model, const Target& target, const FitState& state,
                    const Vae* vae) {
    const fs::path out(job.out);
    const int w = target.width, h = target.height;
    RenderOptions ro = RenderOptions::from_scene(model.scene(), w, h, job.final_spp, job.options.seed + 1);
    TermFilms<kLatentChannels> films =
        render_latent_terms<kLatentChannels>(model.scene(), model.spectra(), model.terms(), ro);
    const std::vector<float> toned = toned_sum(films, job.options.tone);
    const double final_loss = huber_loss(toned.data(), target.data.data(), toned.size(), 1.f, nullptr);
    write_text_atomic((out / "params.json").string(), model.params().to_json());
    write_text_atomic((out / "fit.json").string(), fit_manifest(job, w, h, final_loss, state).dump(2));
    write_latent((out / "latent.exr").string(), w, h, toned);
    // AOVs of the same view with the same samples: what the refiner reads beside the latent.
    write_refiner_aovs((out / "aov.exr").string(), refiner_view(model.scene(), toned, w, h, ro.spp, ro.seed));
    write_latent((out / "latent_e.exr").string(), w, h, films.e.develop());
    write_latent((out / "latent_a.exr").string(), w, h, films.a.develop());
    write_latent((out / "latent_c.exr").string(), w, h, films.c.develop());
    write_text_atomic((out / "loss.csv").string(), loss_csv(state));
    write_latent_pictures(out, target, toned);
    if (vae) write_decoded(out, *vae, target, toned);
    return final_loss;
}

std::string stage1_summary(const FitState& state, int patience) {
    char buf[160];
    if (patience > 0)
        std::snprintf(buf, sizeof buf, "[fit] best smoothed loss %.5f at iteration %d; %d refused steps",
                      state.best_loss, state.best_iteration, state.skipped_steps);
    else
        std::snprintf(buf, sizeof buf,
                      "[fit] early stopping off: the last iteration's parameters are kept (smoothed loss %.5f); "
                      "%d refused steps",
                      state.best_loss, state.skipped_steps);
    return buf;
}

}  // namespace

void validate(const FitJob& job) {
    // "" raised the filesystem's "cannot create directories: Invalid argument []"
    if (job.out.empty()) throw std::invalid_argument("fit --out: the output folder is empty");
    if (fs::exists(job.out) && !fs::is_directory(job.out))
        throw std::invalid_argument("fit --out " + job.out + ": a file, not a folder");
    check_terms(job.gate, job.terms, "--");
    parameterisation_from_string(job.param);
    if (job.ref_tone != "clip" && job.ref_tone != "reinhard")
        throw std::invalid_argument("--ref-tone is clip or reinhard, got '" + job.ref_tone + "'");
    // the CLI's own checks, here too for callers without it (latentpt.fit in Python)
    auto require = [](bool ok, const char* flag, const char* range, double value) {
        if (ok) return;
        char v[32];
        std::snprintf(v, sizeof v, "%g", value);
        throw std::invalid_argument(std::string("fit ") + flag + " must be " + range + ", got " + v);
    };
    const FitOptions& o = job.options;
    require(o.iterations > 0, "--iterations", "> 0", o.iterations);
    require(o.spp > 0, "--spp", "> 0", o.spp);
    require(job.final_spp > 0, "--final-spp", "> 0", job.final_spp);
    require(o.lr > 0.f && std::isfinite(o.lr), "--lr", "> 0", o.lr);
    require(o.lr_min >= 0.f && std::isfinite(o.lr_min), "--lr-min", ">= 0", o.lr_min);
    require(o.lr_min <= o.lr, "--lr-min", "<= --lr (the schedule falls from --lr to it)", o.lr_min);
    require(o.lr_period > 0, "--lr-period", "> 0", o.lr_period);
    require(o.patience >= 0, "--patience", ">= 0", o.patience);
    require(o.min_delta >= 0.f && std::isfinite(o.min_delta), "--min-delta", ">= 0", o.min_delta);
    require(o.checkpoint_every >= 0, "--checkpoint-every", ">= 0", o.checkpoint_every);
    require(o.reuse_paths >= 0, "--reuse-paths", ">= 0", o.reuse_paths);
    require(job.ref_spp > 0, "--ref-spp", "> 0", job.ref_spp);  // 0 traced an all-black reference
    for (const auto& [flag, value] : {std::pair{"--emission-decay", job.options.emission_decay},
                                      std::pair{"--emitter-response-decay", job.options.emitter_response_decay}})
        if (!(value >= 0.f) || !std::isfinite(value))
            throw std::invalid_argument(std::string(flag) + " must be a finite number >= 0, got " +
                                        std::to_string(value));
    for (float k : o.exposures) require(k > 0.f && std::isfinite(k), "--exposures", "finite numbers > 0", k);
    if (!exposures_other_than_1(o.exposures).empty() && !job.encode)
        throw std::invalid_argument(
            "fit --exposures: a light exposure other than 1 needs --encode (the RGB "
            "reference it scales; a given --target or a synthetic one has none)");
    int w = 0, h = 0;  // checked here, before run_fit touches an existing folder's checkpoint
    if (job.target.empty()) {
        const char* flag = job.encode ? "--encode-res" : "--synthetic-res";
        parse_resolution(job.encode ? job.encode_res : job.synthetic_res, w, h, flag);
        // the latents' renders and adjoint (synthetic), or the RGB reference (encode)
        check_size_fits(w, h, job.encode ? 3 : 2 * kLatentChannels + 1, flag);
    }
    if (job.refiner) validate(job.refine);
}

FitSummary run_fit(const FitJob& job, const Reporter& report) {
    validate(job);
    const Scene scene = load_scene(job.scene, job.defines, job.sampler);
    LatentModel model(scene, parameterisation_from_string(job.param), job.options.seed);
    configure_terms(model, job.gate, job.terms);
    FitOptions o = job.options;
    o.checkpoint_dir = (fs::path(job.out) / "checkpoint").string();

    // Inputs that can be refused are read before the folder is touched: without --resume a fit
    // starts its checkpoint again, and a typo must not cost an earlier fit's.
    std::unique_ptr<Vae> vae;
    if (job.encode) vae = open_vae(job.vae);
    std::optional<Target> given;
    if (!job.target.empty()) given = load_target_exr(job.target);

    const OutputLock lock(job.out);  // before anything is written there
    const bool resume = prepare_checkpoint(o.checkpoint_dir, stage1_settings(job), job.resume, job.restart_if_changed);
    if (!resume) remove_refiners(job.out);  // they were trained on another stage 1's renders
    const Target target = given        ? std::move(*given)
                          : job.encode ? encoded_target(job, scene, *vae, report)
                                       : synthetic_target(job, scene);
    write_latent((fs::path(job.out) / "target.exr").string(), target.width, target.height, target.data);

    FitSummary summary;
    if (resume) {
        summary.state = load_checkpoint(o.checkpoint_dir, model);
        report.say("resuming at iteration " + std::to_string(summary.state.next_iteration));
    }
    const size_t steps_before = summary.state.history.size();
    if (!optimise(model, target, o, summary.state, report)) throw Cancelled("fit");
    // The refiners were trained on the renders of stage 1 as it was; one that took steps now
    // (started again and killed before its refiners, or given more iterations) makes them stale,
    // their checkpoints too.
    const bool stage1_as_before = resume && summary.state.history.size() == steps_before;
    if (!stage1_as_before) remove_refiners(job.out);
    report.say(stage1_summary(summary.state, o.patience));
    save_checkpoint(o.checkpoint_dir, model, summary.state);
    summary.latent_width = target.width;
    summary.latent_height = target.height;
    summary.final_loss = write_stage1(job, model, target, summary.state, vae.get());
    report.say("wrote " + job.out +
               "/{params.json, latent*.exr, aov.exr, loss.csv, target|render|diff.png}; Huber loss at " +
               std::to_string(job.final_spp) + " spp: " + std::to_string(summary.final_loss));
    if (job.refiner) {
        RefineJob r = job.refine;
        r.fitdir = job.out;
        r.train.seed = job.options.seed;
        r.resume = stage1_as_before;
        r.restart_if_changed = job.restart_if_changed;
        summary.refined = run_refine(r, report);
    }
    return summary;
}

}  // namespace lpt::pipeline
