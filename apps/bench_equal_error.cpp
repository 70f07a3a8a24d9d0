// `latentpt bench --equal-error <fitdir>`: the paper's runtime comparison at equal error.
//   latent space: the latent renderer (fitted model) vs RGB path tracing + VAE encoding, both
//     judged by latent MSE against the fit's target (the encoded high-spp reference);
//   image space: latent rendering + VAE decoding vs RGB path tracing, judged by RGB MSE against
//     the display-mapped reference (reference_rgb.exr).
// Each side renders at doubling spp, timed in this process. The threshold is 1.05 × the latent
// renderer's best error (its model-error floor), and each side's time is that of the smallest
// spp at or below it. docs/performance.md.
#include "apps/commands.h"
#include "pipeline/fit_folder.h"
#include "pipeline/reference.h"
#include "autodiff/loss.h"
#include "core/image_io.h"
#include "integrators/path.h"
#include "vae/vae.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

namespace lpt::app {

namespace fs = std::filesystem;

namespace {

double mse(const std::vector<float>& a, const std::vector<float>& b) { return mse_loss(a.data(), b.data(), a.size()); }

double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Point {
    int spp = 0;
    double render_s = 0, vae_s = 0;  ///< rendering; decode (latent side) or encode (RGB side)
    double latent_mse = 0, rgb_mse = 0;
};

/// Seconds of the first point whose error is ≤ threshold (NaN if none); `with_vae` adds the
/// VAE pass to the rendering time.
double time_to(const std::vector<Point>& pts, double threshold, bool latent_error, bool with_vae) {
    for (const Point& p : pts)
        if ((latent_error ? p.latent_mse : p.rgb_mse) <= threshold) return p.render_s + (with_vae ? p.vae_s : 0.0);
    return std::numeric_limits<double>::quiet_NaN();
}

/// "latent is 6.60x faster" (or slower), or which side never reached the threshold: no ratio then.
std::string verdict(double latent_s, double rgb_s) {
    if (std::isnan(latent_s)) return "the latent side did not reach it (no ratio)";
    if (std::isnan(rgb_s)) return "the RGB side did not reach it within its spp range (no ratio)";
    char buf[64];
    std::snprintf(buf, sizeof buf, "latent is %.2fx %s", rgb_s >= latent_s ? rgb_s / latent_s : latent_s / rgb_s,
                  rgb_s >= latent_s ? "faster" : "slower");
    return buf;
}

/// Time for each side to reach the latent renderer's error floor × 1.05, in latent and image space.
void print_equal_error(const std::vector<Point>& lat, const std::vector<Point>& rgb) {
    double best_latent = 1e300, best_rgb = 1e300;
    for (const Point& p : lat)
        best_latent = std::min(best_latent, p.latent_mse), best_rgb = std::min(best_rgb, p.rgb_mse);
    const double tl = 1.05 * best_latent, tr = 1.05 * best_rgb;
    const double lat_l = time_to(lat, tl, true, false), rgb_l = time_to(rgb, tl, true, true);
    const double lat_r = time_to(lat, tr, false, true), rgb_r = time_to(rgb, tr, false, false);
    std::printf("\nlatent space, MSE <= %.5f: latent renderer %.4f s, RGB path tracing + encode %.4f s -> %s\n", tl,
                lat_l, rgb_l, verdict(lat_l, rgb_l).c_str());
    std::printf("image space,  MSE <= %.6f: latent render + decode %.4f s, RGB path tracing %.4f s -> %s\n", tr, lat_r,
                rgb_r, verdict(lat_r, rgb_r).c_str());
    std::printf(
        "(NaN: not reached within the spp range; the thresholds are the latent renderer's error floor x 1.05)\n");
}

}  // namespace

int run_bench_equal_error(const BenchArgs& a) {
    pipeline::FitFolder fit = pipeline::load_fit_folder(a.equal_error, {}, a.sampler);
    const fs::path dir(a.equal_error);
    const int w = fit.latent_width, h = fit.latent_height, W = 8 * w, H = 8 * h;
    if (!fs::exists(dir / "reference_rgb.exr"))
        throw std::runtime_error((dir / "reference_rgb.exr").string() + ": missing (the fit needs --encode)");
    const Image target = read_image((dir / "target.exr").string());
    const Image ref_rgb = read_image((dir / "reference_rgb.exr").string());
    if (target.width != w || target.height != h || ref_rgb.width != W || ref_rgb.height != H || ref_rgb.channels != 3)
        throw std::runtime_error(a.equal_error + ": target.exr / reference_rgb.exr do not match the fit's latent size");
    auto vae = pipeline::open_vae(fit.vae);
    const SceneSpectra<3> rgb_spectra = SceneSpectra<3>::from_description(*fit.scene);
    const uint64_t seed = 1;  // the reference used pipeline::kReferenceSeed: independent samples

    std::printf("%s: %dx%d latents (%dx%d RGB); errors against the fit's reference\n", a.equal_error.c_str(), w, h, W,
                H);
    std::printf("%-8s %6s %10s %10s %12s %12s\n", "method", "spp", "render s", "VAE s", "latent MSE", "RGB MSE");
    std::vector<Point> lat, rgb;
    // The warm-up render (thread pool, BVH caches) is not timed.
    render_toned(*fit.model, RenderOptions::from_scene(*fit.scene, w, h, 1, 0), fit.tone);
    for (int spp = 1; spp <= std::max(1, a.max_spp / 4); spp *= 2) {
        RenderOptions o = RenderOptions::from_scene(*fit.scene, w, h, spp, seed);
        Point p;
        p.spp = spp;
        auto t0 = std::chrono::steady_clock::now();
        std::vector<float> latent = render_toned(*fit.model, o, fit.tone);
        p.render_s = seconds_since(t0);
        t0 = std::chrono::steady_clock::now();
        std::vector<float> img = vae->decode(latent, w, h);
        p.vae_s = seconds_since(t0);
        for (float& v : img) v = std::clamp(v, 0.f, 1.f);  // judged as displayed, like the references
        p.latent_mse = mse(latent, target.data);
        p.rgb_mse = mse(img, ref_rgb.data);
        lat.push_back(p);
        std::printf("%-8s %6d %10.4f %10.4f %12.5f %12.6f\n", "latent", spp, p.render_s, p.vae_s, p.latent_mse,
                    p.rgb_mse);
    }
    for (int spp = 1; spp <= a.max_spp; spp *= 2) {
        RenderOptions o = RenderOptions::from_scene(*fit.scene, W, H, spp, seed);
        Point p;
        p.spp = spp;
        auto t0 = std::chrono::steady_clock::now();
        std::vector<float> img = render_path<3>(*fit.scene, rgb_spectra, o).develop();
        for (float& v : img) v = pipeline::display_value(v, fit.ref_tone);
        p.render_s = seconds_since(t0);
        t0 = std::chrono::steady_clock::now();
        std::vector<float> latent = vae->encode(img, W, H);
        p.vae_s = seconds_since(t0);
        p.latent_mse = mse(latent, target.data);
        p.rgb_mse = mse(img, ref_rgb.data);
        rgb.push_back(p);
        std::printf("%-8s %6d %10.4f %10.4f %12.5f %12.6f\n", "RGB", spp, p.render_s, p.vae_s, p.latent_mse, p.rgb_mse);
    }
    print_equal_error(lat, rgb);
    return 0;
}

}  // namespace lpt::app
