// `latentpt refine <fitdir>` (also stage 2 of `latentpt fit`): trains the per-scene refiner on
// the fit's final render and writes refiner.pt, the refined latent, its decoded PNG, the loss
// curve and metrics.json (decoded rendered / refined / VAE round trip against the reference).
#include "apps/commands.h"
#include "latent/latent_model.h"
#include "autodiff/loss.h"
#include "integrators/aov.h"
#include "core/image_io.h"
#include "refiner/refiner.h"
#include "vae/lpips.h"
#include "vae/vae.h"
#include <nlohmann/json.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

namespace lpt::app {

namespace fs = std::filesystem;

namespace {

Image read_checked(const fs::path& p, int channels, int w, int h) {
    if (!fs::exists(p)) throw std::runtime_error(p.string() + ": missing (run latentpt fit first)");
    Image img = read_image(p.string());
    if (img.channels != channels || (w > 0 && (img.width != w || img.height != h)))
        throw std::runtime_error(p.string() + ": expected " + (w > 0 ? std::to_string(w) + "x" + std::to_string(h) + "x" : std::string()) +
                                 std::to_string(channels) + ", found " + std::to_string(img.width) + "x" + std::to_string(img.height) + "x" +
                                 std::to_string(img.channels));
    return img;
}

/// RGB metrics of a decoded latent against the reference image (both in [0, 1] display values).
nlohmann::json rgb_metrics(std::vector<float> rgb, const std::vector<float>& ref, int w, int h, const Lpips* lpips) {
    for (float& v : rgb) v = std::clamp(v, 0.f, 1.f);
    nlohmann::json j = {{"rgb_mse_x100", 100.0 * mse_loss(rgb.data(), ref.data(), rgb.size())}};
    if (lpips && w >= Lpips::kMinSize && h >= Lpips::kMinSize) j["rgb_lpips"] = lpips->distance(rgb, ref, w, h);
    return j;
}

double latent_mse(const std::vector<float>& a, const std::vector<float>& b) { return mse_loss(a.data(), b.data(), a.size()); }

}  // namespace

RefinerInput refiner_view(const Scene& scene, std::vector<float> latent, int w, int h, int spp, uint64_t seed) {
    AovImages aov = render_aovs(scene, SceneSpectra<3>::from_description(scene), w, h, spp, seed);
    RefinerInput in;
    in.width = w;
    in.height = h;
    in.latent = std::move(latent);
    in.normal = std::move(aov.normal);
    in.distance = std::move(aov.distance);
    return in;
}

void write_refiner_aovs(const std::string& path, const RefinerInput& in) {
    Image img{in.width, in.height, 4, {}, {"N.X", "N.Y", "N.Z", "Z"}};
    for (size_t i = 0; i < in.distance.size(); ++i) img.data.insert(img.data.end(), {in.normal[3 * i], in.normal[3 * i + 1], in.normal[3 * i + 2], in.distance[i]});
    write_exr(path, img);
}

RefinerInput load_refiner_input(const std::string& latent_exr, const std::string& aov_exr) {
    Image lat = read_checked(latent_exr, kLatentChannels, 0, 0);
    Image aov = read_checked(aov_exr, 4, lat.width, lat.height);
    RefinerInput in;
    in.width = lat.width;
    in.height = lat.height;
    in.latent = lat.data;
    // By name: OpenEXR files list Z first whatever order they were written in.
    int idx[4];
    const char* names[4] = {"N.X", "N.Y", "N.Z", "Z"};
    for (int k = 0; k < 4; ++k) {
        auto it = std::find(aov.channel_names.begin(), aov.channel_names.end(), names[k]);
        if (it == aov.channel_names.end()) throw std::runtime_error(aov_exr + ": no channel '" + names[k] + "' (expected N.X N.Y N.Z Z)");
        idx[k] = int(it - aov.channel_names.begin());
    }
    for (size_t i = 0; i < size_t(lat.width) * lat.height; ++i) {
        in.normal.insert(in.normal.end(), {aov.data[4 * i + idx[0]], aov.data[4 * i + idx[1]], aov.data[4 * i + idx[2]]});
        in.distance.push_back(aov.data[4 * i + idx[3]]);
    }
    return in;
}

int run_refine(const RefineArgs& a) {
    const fs::path dir(a.fitdir);
    RefinerInput in = load_refiner_input((dir / "latent.exr").string(), (dir / "aov.exr").string());
    const int w = in.width, h = in.height;
    const Image target = read_checked(dir / "target.exr", kLatentChannels, w, h);
    const VaeSource vae_source = manifest_vae((dir / "fit.json").string());
    std::unique_ptr<Vae> vae;
    std::unique_ptr<Lpips> lpips;
    if (vae_present(vae_source)) vae = open_vae(vae_source);
    const std::string lpips_dir = default_lpips_dir(a.lpips_dir);
    if (fs::exists(fs::path(lpips_dir) / "lpips_squeeze_v0.1.safetensors")) lpips = Lpips::load(lpips_dir);
    if ((!vae || !lpips) && !a.quiet)
        std::cerr << "note: no " << (vae ? "LPIPS weights in " + lpips_dir : "VAE (" + default_vae_dir(vae_source.dir) + ")") << ": refiner trains on latent MSE + SSIM only\n";

    // The image the decoded latents are judged against: the RGB reference when the fit encoded
    // one, else the decoded target.
    std::vector<float> ref_rgb;
    if (fs::exists(dir / "reference_rgb.exr")) ref_rgb = read_checked(dir / "reference_rgb.exr", 3, 8 * w, 8 * h).data;
    else if (vae) ref_rgb = vae->decode(target.data, w, h);

    // Distances enter scaled by the training view's mean hit distance, so a scene in
    // millimetres and one in metres feed the network the same numbers.
    double dsum = 0;
    int dn = 0;
    for (float d : in.distance)
        if (d > 0) dsum += d, ++dn;
    RefinerConfig cfg;
    cfg.latent_channels = kLatentChannels;
    cfg.expansion = a.expansion;
    cfg.squash = a.squash;
    cfg.dropout = a.dropout;
    cfg.distance_scale = dn ? float(dsum / dn) : 1.f;
    auto refiner = Refiner::create(cfg, a.seed);

    RefinerTrainOptions o;
    o.iterations = a.iterations;
    o.lr = a.lr;
    o.w_mse = a.w_mse;
    o.w_ssim = a.w_ssim;
    o.w_lpips = a.w_lpips;
    o.crop = a.crop;
    o.lpips_crop = a.lpips_crop;
    o.patience = a.patience;
    o.seed = a.seed;
    o.checkpoint_every = a.checkpoint_every;
    o.checkpoint_path = (dir / "refiner_checkpoint.pt").string();
    o.resume = a.resume && fs::exists(o.checkpoint_path);
    double last_print = -1;
    auto on_iteration = [&](const RefinerRecord& r) {
        if (a.quiet) return true;
        if (r.seconds - last_print < 0.25 && r.iteration + 1 < o.iterations) return true;
        last_print = r.seconds;
        const double rate = (r.iteration + 1) / std::max(1e-9, r.seconds);
        std::fprintf(stderr, "\r[refine] it %d/%d | loss %.4f (smoothed %.4f; mse %.4f dssim %.4f lpips %.4f) | %.1f it/s | ETA %.0f s   ",
                     r.iteration + 1, o.iterations, r.loss, r.smoothed, r.mse, r.dssim, r.lpips, rate, (o.iterations - r.iteration - 1) / rate);
        return true;
    };
    RefinerTrainResult res = refiner->train(in, target.data, ref_rgb.empty() ? nullptr : &ref_rgb, vae.get(), lpips.get(), o, on_iteration);
    if (!a.quiet) std::fprintf(stderr, "\n[refine] best smoothed loss %.5f at iteration %d\n", res.best_loss, res.best_iteration);
    refiner->save((dir / "refiner.pt").string());

    const std::vector<float> refined = refiner->refine(in);
    write_exr((dir / "latent_refined.exr").string(), Image{w, h, kLatentChannels, refined, {}});
    std::ostringstream csv;
    csv << "iteration,loss,smoothed_loss,mse,dssim,lpips,seconds\n";
    for (const RefinerRecord& r : res.history)
        csv << r.iteration << "," << r.loss << "," << r.smoothed << "," << r.mse << "," << r.dssim << "," << r.lpips << "," << r.seconds << "\n";
    write_text_atomic((dir / "refiner_loss.csv").string(), csv.str());

    const double seconds = res.history.empty() ? 0.0 : res.history.back().seconds;
    nlohmann::json m = {{"refiner", {{"expansion", cfg.expansion}, {"parameters", refiner->parameter_count()}, {"iterations", res.history.size()},
                                     {"best_iteration", res.best_iteration}, {"seconds", seconds},
                                     {"seconds_per_iteration", res.history.empty() ? 0.0 : seconds / double(res.history.size())},
                                     {"crop", a.crop}, {"lpips_crop", a.lpips_crop}}},
                        {"rendered", {{"latent_mse", latent_mse(in.latent, target.data)}}},
                        {"refined", {{"latent_mse", latent_mse(refined, target.data)}}}};
    if (vae && !ref_rgb.empty()) {
        const int iw = 8 * w, ih = 8 * h;
        std::vector<float> dec_rendered = vae->decode(in.latent, w, h), dec_refined = vae->decode(refined, w, h);
        m["rendered"].update(rgb_metrics(dec_rendered, ref_rgb, iw, ih, lpips.get()));
        m["refined"].update(rgb_metrics(dec_refined, ref_rgb, iw, ih, lpips.get()));
        if (fs::exists(dir / "reference_rgb.exr")) m["vae_roundtrip"] = rgb_metrics(vae->decode(vae->encode(ref_rgb, iw, ih), w, h), ref_rgb, iw, ih, lpips.get());
        m["reference"] = fs::exists(dir / "reference_rgb.exr") ? "reference_rgb.exr (path-traced RGB)" : "decoded target.exr";
        write_png_display((dir / "decoded_refined.png").string(), Image{iw, ih, 3, dec_refined, {}});
    }
    write_text_atomic((dir / "metrics.json").string(), m.dump(2));
    if (!a.quiet) {
        std::cerr << "wrote " << a.fitdir << "/{refiner.pt, latent_refined.exr, refiner_loss.csv, metrics.json" << (vae ? ", decoded_refined.png" : "") << "}\n";
        auto show = [&](const char* k) {
            if (!m.contains(k)) return;
            const auto& j = m[k];
            std::fprintf(stderr, "  %-14s", k);
            if (j.contains("latent_mse")) std::fprintf(stderr, " latent MSE %.5f", j["latent_mse"].get<double>());
            if (j.contains("rgb_mse_x100")) std::fprintf(stderr, " | RGB MSE×100 %.4f", j["rgb_mse_x100"].get<double>());
            if (j.contains("rgb_lpips")) std::fprintf(stderr, " | LPIPS %.4f", j["rgb_lpips"].get<double>());
            std::fprintf(stderr, "\n");
        };
        show("rendered");
        show("refined");
        show("vae_roundtrip");
    }
    return 0;
}

}  // namespace lpt::app
