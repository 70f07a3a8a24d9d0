// `latentpt render <fitdir> --edit edits.json --out outdir/`: the fitted latent scene under
// camera/light/object edits, frame by frame: latent EXR (tone-mapped, what the VAE reads),
// decoded PNG, and with --reference the RGB path trace of the same edit encoded by the VAE and
// per-frame latent errors in metrics.csv. With the fit's refiner.pt, each frame is also refined
// (frame_NNNN_refined.exr) and frame_NNNN.png shows the refined latent decoded.
#include "apps/commands.h"
#include "apps/fit_folder.h"
#include "autodiff/fit.h"
#include "autodiff/loss.h"
#include "core/image_io.h"
#include "core/scene_edit.h"
#include "core/scene_loader.h"
#include "refiner/refiner.h"
#include "vae/lpips.h"
#include "vae/ssim.h"
#include "vae/vae.h"
#include <algorithm>
#include <nlohmann/json.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace lpt::app {

namespace fs = std::filesystem;

int run_render_edit(const RenderArgs& a) {
    const fs::path dir(a.scene);
    if (!fs::is_directory(dir)) throw std::runtime_error(a.scene + ": --edit needs a fit folder (made by latentpt fit)");
    FitFolder fit = load_fit_folder(a.scene, a.defines);
    Scene& scene = *fit.scene;
    LatentModel& model = *fit.model;
    const ToneCurve tone = fit.tone;

    int w = fit.latent_width, h = fit.latent_height;
    if (!a.res.empty()) parse_resolution(a.res, w, h);  // latent resolution may differ from training
    EditSequence edits = load_edits(a.edit, scene);
    std::vector<TriangleMesh> original;
    for (const Shape& s : scene.shapes) original.push_back(s.mesh);
    const Camera original_camera = scene.camera;
    const VaeSource& vae_source = fit.vae;
    const bool have_vae = vae_present(vae_source);
    if (a.reference && !have_vae) throw std::runtime_error("--reference needs the fit's VAE to encode references; not found: " + default_vae_dir(vae_source.dir));
    if (!have_vae && !a.quiet) std::cerr << "note: the fit's VAE is not here (" << default_vae_dir(vae_source.dir) << "): writing latents only\n";

    const fs::path out(a.out.empty() || a.out == "render.exr" ? "edit-out" : a.out);
    fs::create_directories(out);
    // Stage 2, when the fit trained one: every frame is refined from its latent and AOVs.
    std::unique_ptr<Refiner> refiner;
    if (fs::exists(dir / "refiner.pt")) refiner = Refiner::load((dir / "refiner.pt").string());
    else if (!a.quiet) std::cerr << "note: " << (dir / "refiner.pt").string() << " not found: frames are not refined\n";
    std::unique_ptr<Vae> vae;
    std::unique_ptr<Lpips> lpips;
    if (have_vae) vae = open_vae(vae_source);
    if (a.reference && have_vae) {
        const std::string lpips_dir = default_lpips_dir("");
        if (fs::exists(fs::path(lpips_dir) / "lpips_squeeze_v0.1.safetensors")) lpips = Lpips::load(lpips_dir);
        else if (!a.quiet) std::cerr << "note: no LPIPS weights at " << lpips_dir << ": rgb_lpips left empty\n";
    }
    std::ostringstream csv;
    const char* columns = "latent_mse,latent_psnr,latent_dssim,rgb_mse_x100,rgb_ssim,rgb_lpips";
    csv << "frame,t," << columns;
    if (refiner) {
        std::string c = columns, r;
        for (size_t p = 0, q; p <= c.size(); p = q + 1) {
            q = c.find(',', p);
            if (q == std::string::npos) q = c.size();
            r += ",refined_" + c.substr(p, q - p);
        }
        csv << r;
    }
    csv << "\n";
    // Latent and decoded-image errors of one frame against the encoded reference (docs/metrics.md):
    // latent MSE, PSNR over the data range 6, D-SSIM = 1 − SSIM (range 6); decoded RGB (clamped
    // to [0, 1]) MSE × 100, SSIM, LPIPS against the display-mapped reference. Empty when the image
    // is below a metric's minimum size.
    auto frame_metrics = [&](const std::vector<float>& latent, const std::vector<float>& ref, const std::vector<float>& ref_rgb) {
        const double mse = mse_loss(latent.data(), ref.data(), ref.size());
        std::ostringstream o;
        o << "," << mse << "," << 10.0 * std::log10(36.0 / std::max(mse, 1e-12)) << ",";  // data range 6 (±3)
        if (w >= kSsimWindow && h >= kSsimWindow) o << 1.0 - ssim(latent.data(), ref.data(), w, h, kLatentChannels, kLatentDataRange);
        o << ",";
        if (vae) {
            std::vector<float> rgb = vae->decode(latent, w, h);
            for (float& v : rgb) v = std::clamp(v, 0.f, 1.f);
            o << 100.0 * mse_loss(rgb.data(), ref_rgb.data(), rgb.size()) << ",";
            if (8 * w >= kSsimWindow && 8 * h >= kSsimWindow) o << ssim(rgb.data(), ref_rgb.data(), 8 * w, 8 * h, 3, 1.0);
            o << ",";
            if (lpips && 8 * w >= Lpips::kMinSize && 8 * h >= Lpips::kMinSize) o << lpips->distance(rgb, ref_rgb, 8 * w, 8 * h);
        } else {
            o << ",,";
        }
        return o.str();
    };
    for (int i = 0; i < edits.frames; ++i) {
        const float t = float(i) / float(edits.frames);
        apply_edits(edits, t, original, original_camera, scene);
        RenderOptions ro = RenderOptions::from_scene(scene);
        ro.width = w;
        ro.height = h;
        ro.spp = a.spp > 0 ? a.spp : 64;
        ro.seed = a.seed + uint64_t(i);
        std::vector<float> latent = render_toned(model, ro, tone), refined;
        char name[64];
        std::snprintf(name, sizeof name, "frame_%04d", i);
        const std::string stem = (out / name).string();
        write_exr(stem + "_latent.exr", Image{w, h, kLatentChannels, latent, {}});
        if (refiner) {
            // Same spp and seed as the latent: an identity edit reproduces the fit's refined latent.
            const RefinerInput view = refiner_view(scene, latent, w, h, ro.spp, ro.seed);
            write_refiner_aovs(stem + "_aov.exr", view);
            refined = refiner->refine(view);
            write_exr(stem + "_refined.exr", Image{w, h, kLatentChannels, refined, {}});
        }
        if (vae) {
            // frame_NNNN.png is the result (refined when there is a refiner); _rendered.png the unrefined one.
            write_png_display(stem + (refiner ? "_rendered.png" : ".png"), Image{8 * w, 8 * h, 3, vae->decode(latent, w, h), {}});
            if (refiner) write_png_display(stem + ".png", Image{8 * w, 8 * h, 3, vae->decode(refined, w, h), {}});
        }
        if (a.reference) {
            // The edited scene file is not on disk: path trace this Scene directly, or take the
            // frame from --reference-cache (experiments compare several fits on one sequence).
            std::vector<float> ref_rgb, ref;
            const std::string& tone_name = fit.ref_tone;
            fs::path cached;
            if (!a.reference_cache.empty()) {
                char key[160];
                std::snprintf(key, sizeof key, "%s_%dx%d_%dspp_%s_%s.exr", fs::path(a.edit).stem().string().c_str(), 8 * w, 8 * h, a.ref_spp,
                              tone_name.c_str(), name);
                cached = fs::path(a.reference_cache) / key;
            }
            if (!cached.empty() && fs::exists(cached)) {
                Image img = read_image(cached.string());
                if (img.width != 8 * w || img.height != 8 * h || img.channels != 3) throw std::runtime_error(cached.string() + ": cached reference has the wrong size");
                ref_rgb = img.data;
                ref = vae->encode(ref_rgb, 8 * w, 8 * h);
                write_png_display(stem + "_reference.png", Image{8 * w, 8 * h, 3, ref_rgb, {}});
            } else {
                ref = encoded_reference_of(scene, 8 * w, 8 * h, a.ref_spp, tone_name, *vae, true, stem + "_reference.png", &ref_rgb);
                if (!cached.empty()) {
                    fs::create_directories(cached.parent_path());
                    write_exr(cached.string(), Image{8 * w, 8 * h, 3, ref_rgb, {"R", "G", "B"}});
                }
            }
            csv << i << "," << t << frame_metrics(latent, ref, ref_rgb);
            if (refiner) csv << frame_metrics(refined, ref, ref_rgb);
            csv << "\n";
        }
        if (!a.quiet) std::fprintf(stderr, "\r[edit] frame %d/%d   ", i + 1, edits.frames);
    }
    if (a.reference) write_text_atomic((out / "metrics.csv").string(), csv.str());
    if (!a.quiet) std::cerr << "\nwrote " << edits.frames << " frames to " << out.string() << "\n";
    return 0;
}

}  // namespace lpt::app
