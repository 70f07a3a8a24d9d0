// `latentpt render <fitdir> --edit edits.json --out outdir/`: the fitted latent scene under
// camera/light/object edits, frame by frame: latent EXR (tone-mapped, what the VAE reads),
// decoded PNG, and with --reference the RGB path trace of the same edit encoded by the VAE and
// per-frame latent errors in metrics.csv. The refiner (issue 5) will add a refined latent.
#include "apps/commands.h"
#include "autodiff/fit.h"
#include "core/image_io.h"
#include "core/scene_edit.h"
#include "core/scene_loader.h"
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
    const std::string manifest_path = (dir / "fit.json").string();
    std::ifstream mf(manifest_path);
    if (!mf) throw std::runtime_error(manifest_path + ": missing: not a latentpt fit folder");
    nlohmann::json m;
    try {
        m = nlohmann::json::parse(mf);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(manifest_path + ": malformed: " + e.what());
    }
    std::map<std::string, std::string> defines = m.value("defines", std::map<std::string, std::string>{});
    for (const auto& [k, v] : a.defines) defines[k] = v;
    Scene scene = load_scene(m.at("scene").get<std::string>(), defines);
    LatentModel model(scene, parameterisation_from_string(m.value("param", "code")), 0);
    const std::string params_path = (dir / "params.json").string();
    std::ifstream pf(params_path);
    if (!pf) throw std::runtime_error(params_path + ": missing");
    std::stringstream ps;
    ps << pf.rdbuf();
    model.params().load_json(ps.str(), params_path);
    model.terms().gate = m.value("gate", "shadowed") == "visible" ? OcclusionGate::Visible : OcclusionGate::Shadowed;
    const std::string terms = m.value("terms", "eac");
    model.terms().emission = terms.find('e') != std::string::npos;
    model.terms().ambient = terms.find('a') != std::string::npos;
    model.terms().occlusion = terms.find('c') != std::string::npos;
    model.sync();
    const ToneCurve tone = parse_tone_curve(m.value("tone", "clip"));

    int w = m.at("latent_width"), h = m.at("latent_height");
    if (!a.res.empty()) parse_resolution(a.res, w, h);  // latent resolution may differ from training
    EditSequence edits = load_edits(a.edit, scene);
    std::vector<TriangleMesh> original;
    for (const Shape& s : scene.shapes) original.push_back(s.mesh);
    const Camera original_camera = scene.camera;
    const std::string vae_dir = m.value("vae_dir", default_vae_dir(""));
    const bool have_vae = fs::exists(fs::path(vae_dir) / "taesd3_decoder.safetensors");
    if (!have_vae && !a.quiet) std::cerr << "note: no VAE at " << vae_dir << ": writing latents only\n";

    const fs::path out(a.out.empty() || a.out == "render.exr" ? "edit-out" : a.out);
    fs::create_directories(out);
    std::ostringstream csv;
    csv << "frame,t,latent_mse,latent_psnr,rgb_ssim,rgb_lpips\n";
    // Image metrics of the decoded frame against the decoded-space reference (docs/metrics.md).
    std::unique_ptr<Vae> vae;
    std::unique_ptr<Lpips> lpips;
    if (a.reference && have_vae) {
        vae = load_taesd(vae_dir);
        const fs::path lpips_dir = fs::path(vae_dir).parent_path() / "lpips";
        if (fs::exists(lpips_dir)) lpips = Lpips::load(lpips_dir.string());
        else if (!a.quiet) std::cerr << "note: no LPIPS weights at " << lpips_dir.string() << ": rgb_lpips left empty\n";
    }
    for (int i = 0; i < edits.frames; ++i) {
        const float t = float(i) / float(edits.frames);
        apply_edits(edits, t, original, original_camera, scene);
        RenderOptions ro = RenderOptions::from_scene(scene);
        ro.width = w;
        ro.height = h;
        ro.spp = a.spp > 0 ? a.spp : 64;
        ro.seed = a.seed + uint64_t(i);
        std::vector<float> latent = render_toned(model, ro, tone);
        char name[64];
        std::snprintf(name, sizeof name, "frame_%04d", i);
        write_exr((out / (std::string(name) + "_latent.exr")).string(), Image{w, h, kLatentChannels, latent, {}});
        if (have_vae) {
            VaeArgs d{(out / (std::string(name) + "_latent.exr")).string(), (out / (std::string(name) + ".png")).string(), vae_dir, true};
            run_decode(d);
        }
        if (a.reference) {
            // The edited scene file is not on disk: path trace this Scene directly.
            std::vector<float> ref_rgb;
            std::vector<float> ref = encoded_reference_of(scene, 8 * w, 8 * h, a.ref_spp, m.value("ref_tone", "clip"), vae_dir, true,
                                                          (out / (std::string(name) + "_reference.png")).string(), &ref_rgb);
            double mse = 0;
            for (size_t k = 0; k < ref.size(); ++k) mse += double(latent[k] - ref[k]) * (latent[k] - ref[k]);
            mse /= double(ref.size());
            csv << i << "," << t << "," << mse << "," << 10.0 * std::log10(36.0 / std::max(mse, 1e-12));  // data range 6 (±3)
            std::string s_ssim, s_lpips;
            if (vae) {
                std::vector<float> rgb = vae->decode(latent, w, h);
                for (float& v : rgb) v = std::clamp(v, 0.f, 1.f);
                if (8 * w >= 11 && 8 * h >= 11) s_ssim = std::to_string(ssim(rgb.data(), ref_rgb.data(), 8 * w, 8 * h, 3, 1.0));
                if (lpips && 8 * w >= Lpips::kMinSize && 8 * h >= Lpips::kMinSize) s_lpips = std::to_string(lpips->distance(rgb, ref_rgb, 8 * w, 8 * h));
            }
            csv << "," << s_ssim << "," << s_lpips << "\n";
        }
        if (!a.quiet) std::fprintf(stderr, "\r[edit] frame %d/%d   ", i + 1, edits.frames);
    }
    if (a.reference) write_text_atomic((out / "metrics.csv").string(), csv.str());
    if (!a.quiet) std::cerr << "\nwrote " << edits.frames << " frames to " << out.string() << "\n";
    return 0;
}

}  // namespace lpt::app
