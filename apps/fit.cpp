// `latentpt fit`: stage 1 of the paper's pipeline. Fits per-shape latent parameters to a target
// latent map and writes params.json, the rendered latent (and its three terms), loss.csv,
// pictures of target / render / difference, and checkpoints (--resume continues a killed fit).
#include "apps/commands.h"
#include "autodiff/fit.h"
#include "autodiff/loss.h"
#include "core/image_io.h"
#include "core/latent_viz.h"
#include "core/scene_loader.h"
#include "vae/vae.h"
#include "refiner/refiner.h"
#include <nlohmann/json.hpp>
#include <filesystem>
#include <iostream>
#include <sstream>

namespace lpt::app {

namespace fs = std::filesystem;

namespace {

std::vector<float> load_target(const std::string& path, int& w, int& h) {
    Image img = read_image(path);
    if (img.channels != kLatentChannels)
        throw std::runtime_error(path + ": target has " + std::to_string(img.channels) + " channels, a latent map needs " + std::to_string(kLatentChannels) +
                                 " (an RGB image needs --encode, which arrives with the VAE)");
    size_t bad = 0;
    if (!check_finite(img.data.data(), img.data.size(), &bad))
        throw std::runtime_error(path + ": value at pixel (" + std::to_string(bad / kLatentChannels % img.width) + ", " +
                                 std::to_string(bad / kLatentChannels / img.width) + "), channel " + std::to_string(bad % kLatentChannels) +
                                 " is not finite");
    w = img.width;
    h = img.height;
    return img.data;
}

void write_latent(const std::string& path, int w, int h, const std::vector<float>& data) {
    Image img{w, h, kLatentChannels, data, {}};
    write_exr(path, img);
}

std::string loss_csv(const FitState& st) {
    std::ostringstream out;
    out << "iteration,loss,smoothed_loss,lr,seconds\n";
    for (const FitRecord& r : st.history) out << r.iteration << "," << r.loss << "," << r.smoothed << "," << r.lr << "," << r.seconds << "\n";
    return out.str();
}

}  // namespace

int run_fit(const FitArgs& a) {
    Scene scene = load_scene(a.scene, a.defines);
    LatentModel model(scene, parameterisation_from_string(a.param), a.seed);
    model.terms().gate = a.gate == "visible" ? OcclusionGate::Visible : OcclusionGate::Shadowed;
    model.terms().emission = a.terms.find('e') != std::string::npos;
    model.terms().ambient = a.terms.find('a') != std::string::npos;
    model.terms().occlusion = a.terms.find('c') != std::string::npos;

    FitOptions o;
    o.iterations = a.iterations;
    o.spp = a.spp;
    o.seed = a.seed;
    o.lr = a.lr;
    o.lr_min = a.lr_min;
    o.lr_period = a.lr_period;
    o.patience = a.patience;
    o.min_delta = a.min_delta;
    o.tone = parse_tone_curve(a.tone);
    o.checkpoint_every = a.checkpoint_every;
    o.reuse_paths = a.reuse_paths;
    o.checkpoint_dir = (fs::path(a.out) / "checkpoint").string();

    int w = 0, h = 0;
    std::vector<float> target;
    fs::create_directories(a.out);
    if (!a.target.empty()) {
        target = load_target(a.target, w, h);
        write_latent((fs::path(a.out) / "target.exr").string(), w, h, target);
    } else if (a.encode) {
        // The paper's target: path-traced RGB, tone-mapped, encoded by the VAE (TAESD3).
        int iw = 0, ih = 0;
        parse_resolution(a.encode_res, iw, ih);
        std::vector<float> ref_rgb;
        target = encoded_reference_of(load_scene(a.scene, a.defines), iw, ih, a.ref_spp, a.ref_tone, *open_vae(a.vae), a.quiet,
                                      (fs::path(a.out) / "reference.png").string(), &ref_rgb);
        // The refiner's LPIPS and metrics.json compare decoded latents with this image.
        write_exr((fs::path(a.out) / "reference_rgb.exr").string(), Image{iw, ih, 3, ref_rgb, {"R", "G", "B"}});
        w = iw / 8;
        h = ih / 8;
        write_latent((fs::path(a.out) / "target.exr").string(), w, h, target);
    } else {
        // A target the latent renderer makes itself from random parameters: for trying the fit
        // without a VAE, and the test suite's convergence check.
        parse_resolution(a.synthetic_res, w, h);
        Scene truth_scene = load_scene(a.scene, a.defines);
        LatentModel truth(truth_scene, parameterisation_from_string(a.param), a.synthetic_seed);
        RenderOptions ro = RenderOptions::from_scene(truth_scene);
        ro.width = w;
        ro.height = h;
        ro.spp = a.final_spp;
        ro.seed = a.synthetic_seed;
        target = render_toned(truth, ro, o.tone);
        write_latent((fs::path(a.out) / "target.exr").string(), w, h, target);
    }

    FitState state;
    if (a.resume) {
        state = load_checkpoint(o.checkpoint_dir, model);
        if (!a.quiet) std::cerr << "resuming at iteration " << state.next_iteration << "\n";
    }
    const int start = state.next_iteration;
    const double seconds_at_start = state.history.empty() ? 0.0 : state.history.back().seconds;
    double last_print = -1.0;
    auto on_iteration = [&](const FitRecord& r, const FitState& st) {
        if (r.refused && st.skipped_steps <= 10)
            std::fprintf(stderr, "\nlatentpt: warning: iteration %d: non-finite gradient, step skipped (%d so far)%s\n", r.iteration, st.skipped_steps,
                         st.skipped_steps == 10 ? "; further warnings suppressed" : "");
        if (a.quiet) return true;
        const int done = r.iteration + 1 - start, total = std::max(1, o.iterations - start);
        const double el = std::max(1e-9, r.seconds - seconds_at_start);
        if (el - last_print < 0.25 && done < total) return true;  // a line every 0.25 s at most
        last_print = el;
        std::fprintf(stderr, "\r[fit] it %d/%d | loss %.5f (smoothed %.5f) | lr %.2e | %.1f it/s | ETA %.0f s   ", r.iteration + 1, o.iterations,
                     r.loss, r.smoothed, r.lr, done / el, el * (total - done) / std::max(1, done));
        return true;
    };
    state = fit_latent(model, target, w, h, o, state, on_iteration);
    if (!a.quiet) {
        // With --patience 0 nothing tracks a best iteration: the last parameters are kept.
        if (state.best_iteration >= 0)
            std::fprintf(stderr, "\n[fit] best smoothed loss %.5f at iteration %d; %d refused steps\n", state.best_loss, state.best_iteration, state.skipped_steps);
        else
            std::fprintf(stderr, "\n[fit] early stopping off: the last iteration's parameters are kept; %d refused steps\n", state.skipped_steps);
    }
    save_checkpoint(o.checkpoint_dir, model, state);

    // Final render of the best parameters at --final-spp.
    RenderOptions ro = RenderOptions::from_scene(model.scene());
    ro.width = w;
    ro.height = h;
    ro.spp = a.final_spp;
    ro.seed = a.seed + 1;
    TermFilms<kLatentChannels> films = render_latent_terms<kLatentChannels>(model.scene(), model.spectra(), model.terms(), ro);
    std::vector<float> linear = films.sum(), toned(linear.size()), diff(linear.size());
    tone_map(o.tone, linear.data(), toned.data(), linear.size());
    for (size_t i = 0; i < toned.size(); ++i) diff[i] = toned[i] - target[i];
    const double final_loss = huber_loss(toned.data(), target.data(), toned.size(), 1.f, nullptr);
    const fs::path out(a.out);
    write_text_atomic((out / "params.json").string(), model.params().to_json());
    // Everything `latentpt render <fitdir> --edit` needs to rebuild this model.
    nlohmann::json manifest = {{"scene", fs::absolute(a.scene).string()}, {"defines", a.defines}, {"param", a.param}, {"gate", a.gate},
                               {"terms", a.terms}, {"tone", a.tone}, {"latent_width", w}, {"latent_height", h}, {"seed", a.seed},
                               {"vae_dir", default_vae_dir(a.vae.dir)}, {"ref_tone", a.ref_tone}};
    if (a.vae.torchscript())
        manifest["vae_torchscript"] = {{"encoder", fs::absolute(a.vae.encoder).string()}, {"decoder", fs::absolute(a.vae.decoder).string()},
                                       {"config", fs::absolute(a.vae.config).string()}};
    // How stage 1 went, for comparing runs (e.g. --reuse-paths) without parsing logs.
    manifest["stage1"] = {{"final_loss", final_loss}, {"final_spp", a.final_spp}, {"iterations_run", state.next_iteration},
                          {"best_iteration", state.best_iteration}, {"seconds", state.history.empty() ? 0.0 : state.history.back().seconds},
                          {"spp", a.spp}, {"reuse_paths", a.reuse_paths}, {"skipped_steps", state.skipped_steps}};
    write_text_atomic((out / "fit.json").string(), manifest.dump(2));
    write_latent((out / "latent.exr").string(), w, h, toned);
    // AOVs of the same view with the same samples: what the refiner reads beside the latent.
    write_refiner_aovs((out / "aov.exr").string(), refiner_view(model.scene(), toned, w, h, ro.spp, ro.seed));
    write_latent((out / "latent_e.exr").string(), w, h, films.e.develop());
    write_latent((out / "latent_a.exr").string(), w, h, films.a.develop());
    write_latent((out / "latent_c.exr").string(), w, h, films.c.develop());
    write_text_atomic((out / "loss.csv").string(), loss_csv(state));
    float scale = 0.f;
    for (float v : target) scale = std::max(scale, std::abs(v));
    write_png_srgb((out / "target.png").string(), latent_grid(target.data(), w, h, kLatentChannels, scale));
    write_png_srgb((out / "render.png").string(), latent_grid(toned.data(), w, h, kLatentChannels, scale));
    write_png_srgb((out / "diff.png").string(), latent_grid(diff.data(), w, h, kLatentChannels, scale));
    if (a.encode) {
        // What a person looks at: the fitted latent decoded to RGB next to the reference.
        VaeArgs d{(out / "latent.exr").string(), (out / "decoded.png").string(), a.vae, true};
        run_decode(d);
        d.input = (out / "target.exr").string();
        d.out = (out / "target_decoded.png").string();
        run_decode(d);
    }
    if (!a.quiet) std::cerr << "wrote " << a.out << "/{params.json, latent*.exr, aov.exr, loss.csv, target|render|diff.png}; Huber loss at " << a.final_spp << " spp: " << final_loss << "\n";
    if (a.refiner) {
        RefineArgs r = a.refine;
        r.fitdir = a.out;
        r.seed = a.seed;
        r.resume = a.resume;
        r.quiet = a.quiet;
        return run_refine(r);
    }
    return 0;
}

}  // namespace lpt::app
