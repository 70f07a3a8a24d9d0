// `latentpt metrics a b`: MSE, PSNR, SSIM and LPIPS between two images of the same size, or MSE,
// PSNR and SSIM between two latent EXRs (docs/metrics.md).
//   * PNG/JPEG (and other non-float formats): display values in [0, 1] as read.
//   * EXR/HDR with 3 or 4 channels: linear RGB, turned into display values as fit's
//     --ref-tone clip does (clip to [0, 1], then x^(1/2.2)). A 4th (alpha) channel is ignored.
//   * EXR with 16 channels: TAESD3 latents, compared as they are over the data range 6
//     ([-3, 3], the decoder's soft-clamp range); no LPIPS (it is an RGB metric).
#include "apps/commands.h"
#include "core/image_io.h"
#include "vae/lpips.h"
#include "vae/ssim.h"
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>

#ifndef LPT_SOURCE_DIR
#define LPT_SOURCE_DIR "."
#endif

namespace lpt::app {

namespace {

namespace fs = std::filesystem;

constexpr int kLatentChannels = 16;

struct Loaded {
    int width = 0, height = 0, channels = 0;  ///< channels of `data` (3 for RGB)
    bool latent = false;
    std::string kind;  ///< how the values were interpreted
    std::vector<float> data;
};

bool is_float_format(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext == ".exr" || ext == ".hdr";
}

Loaded load(const std::string& path) {
    Image img = read_image(path);
    Loaded l;
    l.width = img.width;
    l.height = img.height;
    if (img.channels == kLatentChannels && is_float_format(path)) {
        l.latent = true;
        l.channels = img.channels;
        l.kind = "latent (16 channels)";
        l.data = std::move(img.data);
        return l;
    }
    if (img.channels != 3 && img.channels != 4)
        throw std::runtime_error(path + ": " + std::to_string(img.channels) +
                                 " channels; metrics compares RGB(A) images (3 or 4 channels) or " +
                                 std::to_string(kLatentChannels) + "-channel latent EXRs");
    const bool linear = is_float_format(path);
    l.channels = 3;
    l.kind = linear ? "linear RGB -> display (clip, gamma 1/2.2)" : "display RGB";
    if (img.channels == 4) l.kind += ", alpha ignored";
    l.data.resize(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
        for (int c = 0; c < 3; ++c) {
            float v = img.data[i * img.channels + c];
            if (linear) v = std::pow(std::clamp(v, 0.f, 1.f), 1.f / 2.2f);  // fit --ref-tone clip
            l.data[i * 3 + c] = v;
        }
    return l;
}

std::string json_string(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') o += '\\', o += c;
        else if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            o += buf;
        } else o += c;
    }
    return o + "\"";
}

std::string json_number(const std::optional<double>& v) {
    if (!v || !std::isfinite(*v)) return "null";
    std::ostringstream s;
    s.precision(9);
    s << *v;
    return s.str();
}

}  // namespace

int run_metrics(const MetricsArgs& args) {
    Loaded a = load(args.a), b = load(args.b);
    if (a.latent != b.latent || a.channels != b.channels)
        throw std::runtime_error("metrics needs the same kind of data in both files: " + args.a + " is " + a.kind +
                                 ", " + args.b + " is " + b.kind);
    if (a.width != b.width || a.height != b.height)
        throw std::runtime_error("metrics needs images of the same size: " + args.a + " is " + std::to_string(a.width) +
                                 "x" + std::to_string(a.height) + ", " + args.b + " is " + std::to_string(b.width) +
                                 "x" + std::to_string(b.height));

    const double range = a.latent ? kLatentDataRange : kImageDataRange;
    double se = 0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        const double d = double(a.data[i]) - double(b.data[i]);
        se += d * d;
    }
    const double mse = a.data.empty() ? 0.0 : se / double(a.data.size());
    const double psnr = mse > 0 ? 10.0 * std::log10(range * range / mse) : std::numeric_limits<double>::infinity();

    std::optional<double> ssim_v, lpips_v;
    std::string ssim_note, lpips_note;
    if (a.width >= kSsimWindow && a.height >= kSsimWindow)
        ssim_v = ssim(a.data.data(), b.data.data(), a.width, a.height, a.channels, range);
    else ssim_note = "n/a (image smaller than the 11x11 window)";

    if (a.latent) lpips_note = "n/a (latents; LPIPS is an RGB metric)";
    else if (a.width < Lpips::kMinSize || a.height < Lpips::kMinSize)
        lpips_note =
            "n/a (image smaller than " + std::to_string(Lpips::kMinSize) + "x" + std::to_string(Lpips::kMinSize) + ")";
    else {
        const std::string dir = default_lpips_dir(args.vae_dir);
        if (args.vae_dir.empty() && !fs::exists(dir + "/lpips_squeeze_v0.1.safetensors")) {
            lpips_note = "n/a (no weights in " + dir + "; pass --lpips-dir)";
            std::cerr << "latentpt metrics: warning: LPIPS weights not found in " << dir << ", LPIPS skipped\n";
        } else {
            lpips_v = Lpips::load(dir)->distance(a.data, b.data, a.width, a.height);
        }
    }

    if (args.json) {
        std::cout << "{\"a\": " << json_string(args.a) << ", \"b\": " << json_string(args.b)
                  << ", \"width\": " << a.width << ", \"height\": " << a.height << ", \"channels\": " << a.channels
                  << ", \"kind\": " << json_string(a.latent ? "latent" : "rgb")
                  << ", \"data_range\": " << json_number(range) << ", \"mse\": " << json_number(mse)
                  << ", \"mse_x100\": " << json_number(mse * 100) << ", \"psnr\": " << json_number(psnr)
                  << ", \"ssim\": " << json_number(ssim_v) << ", \"lpips\": " << json_number(lpips_v) << "}\n";
        return 0;
    }
    std::printf("a: %s (%dx%d, %s)\n", args.a.c_str(), a.width, a.height, a.kind.c_str());
    std::printf("b: %s (%dx%d, %s)\n", args.b.c_str(), b.width, b.height, b.kind.c_str());
    std::printf("MSE       %.6g\n", mse);
    std::printf("MSE x100  %.6g\n", mse * 100);
    if (std::isfinite(psnr)) std::printf("PSNR      %.4f dB (data range %g)\n", psnr, range);
    else std::printf("PSNR      inf (identical)\n");
    if (ssim_v) std::printf("SSIM      %.6f (11x11 Gaussian, sigma 1.5, data range %g)\n", *ssim_v, range);
    else std::printf("SSIM      %s\n", ssim_note.c_str());
    if (lpips_v) std::printf("LPIPS     %.6f (v0.1, SqueezeNet)\n", *lpips_v);
    else std::printf("LPIPS     %s\n", lpips_note.c_str());
    return 0;
}

}  // namespace lpt::app
