// `latentpt metrics a b`: MSE, PSNR, SSIM and LPIPS between two images of the same size, or MSE,
// PSNR and SSIM between two latent EXRs (docs/metrics.md).
//   * PNG/JPEG (and other non-float formats): display values in [0, 1] as read.
//   * EXR/HDR with 3 or 4 channels: linear RGB, turned into display values as fit's
//     --ref-tone clip does (clip to [0, 1], then x^(1/2.2)), unless the header marks them as
//     display values already (references, decoded latents: only clipped to [0, 1], as the edit
//     and refine scores clip decoded RGB). A 4th (alpha) channel is ignored.
//   * EXR with 16 channels: TAESD3 latents, compared as they are over the data range 6
//     ([-3, 3], the decoder's soft-clamp range); no LPIPS (it is an RGB metric).
// `latentpt metrics --pairs FILE` scores many pairs in one process (one JSON line each): loading
// libtorch and LPIPS costs ~1 s, more than scoring a 1024² pair (scripts/reference_noise.py).
#include "apps/commands.h"
#include "core/image_io.h"
#include "pipeline/reference.h"
#include "vae/lpips.h"
#include "vae/ssim.h"
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

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

Loaded load(const std::string& path) {
    Image img = read_image(path);
    require_finite_pixels(img, path);  // else "MSE nan ... PSNR inf (identical)"
    Loaded l;
    l.width = img.width;
    l.height = img.height;
    if (img.channels == kLatentChannels && pipeline::float_image_path(path)) {
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
    l.channels = 3;
    switch (pipeline::rgb_values_of(img, path)) {
        case pipeline::RgbValues::Linear:
            l.kind = "linear RGB -> display (clip, gamma 1/2.2)";
            break;
        case pipeline::RgbValues::MarkedDisplay:
            l.kind = "display RGB (EXR marked so), clipped to [0, 1]";
            break;
        case pipeline::RgbValues::Display:
            l.kind = "display RGB";
            break;
    }
    if (img.channels == 4) l.kind += ", alpha ignored";
    l.data = pipeline::display_rgb(img, path);
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

namespace {

struct Scores {
    Loaded a, b;
    double range = 0, mse = 0, psnr = 0;
    std::optional<double> ssim, lpips;
    std::string ssim_note, lpips_note;
};

/// LPIPS's weights, loaded on first use and kept: `--pairs` scores many images in one process.
class LpipsOnce {
public:
    explicit LpipsOnce(std::string dir) : dir_(std::move(dir)) {}
    /// The network, or nullptr with `note` set when no weights are found in the default folder.
    const Lpips* get(std::string& note) {
        if (!tried_) {
            tried_ = true;
            const std::string dir = default_lpips_dir(dir_);
            if (dir_.empty() && !fs::exists(dir + "/lpips_squeeze_v0.1.safetensors")) {
                missing_ = "n/a (no weights in " + dir + "; pass --lpips-dir)";
                std::cerr << "latentpt metrics: warning: LPIPS weights not found in " << dir << ", LPIPS skipped\n";
            } else {
                net_ = Lpips::load(dir);
            }
        }
        if (!net_) note = missing_;
        return net_.get();
    }

private:
    std::string dir_, missing_;
    bool tried_ = false;
    std::unique_ptr<Lpips> net_;
};

Scores score(const std::string& path_a, const std::string& path_b, LpipsOnce& lpips) {
    Scores s;
    s.a = load(path_a);
    s.b = load(path_b);
    const Loaded &a = s.a, &b = s.b;
    if (a.latent != b.latent || a.channels != b.channels)
        throw std::runtime_error("metrics needs the same kind of data in both files: " + path_a + " is " + a.kind +
                                 ", " + path_b + " is " + b.kind);
    if (a.width != b.width || a.height != b.height)
        throw std::runtime_error("metrics needs images of the same size: " + path_a + " is " + std::to_string(a.width) +
                                 "x" + std::to_string(a.height) + ", " + path_b + " is " + std::to_string(b.width) +
                                 "x" + std::to_string(b.height));

    s.range = a.latent ? kLatentDataRange : kImageDataRange;
    double se = 0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        const double d = double(a.data[i]) - double(b.data[i]);
        se += d * d;
    }
    s.mse = a.data.empty() ? 0.0 : se / double(a.data.size());
    s.psnr = s.mse > 0 ? 10.0 * std::log10(s.range * s.range / s.mse) : std::numeric_limits<double>::infinity();

    if (a.width >= kSsimWindow && a.height >= kSsimWindow)
        s.ssim = ssim(a.data.data(), b.data.data(), a.width, a.height, a.channels, s.range);
    else s.ssim_note = "n/a (image smaller than the 11x11 window)";

    if (a.latent) s.lpips_note = "n/a (latents; LPIPS is an RGB metric)";
    else if (a.width < Lpips::kMinSize || a.height < Lpips::kMinSize)
        s.lpips_note =
            "n/a (image smaller than " + std::to_string(Lpips::kMinSize) + "x" + std::to_string(Lpips::kMinSize) + ")";
    else if (const Lpips* net = lpips.get(s.lpips_note)) s.lpips = net->distance(a.data, b.data, a.width, a.height);
    return s;
}

void print_json(const std::string& path_a, const std::string& path_b, const Scores& s) {
    std::cout << "{\"a\": " << json_string(path_a) << ", \"b\": " << json_string(path_b) << ", \"width\": " << s.a.width
              << ", \"height\": " << s.a.height << ", \"channels\": " << s.a.channels
              << ", \"kind\": " << json_string(s.a.latent ? "latent" : "rgb")
              << ", \"data_range\": " << json_number(s.range) << ", \"mse\": " << json_number(s.mse)
              << ", \"mse_x100\": " << json_number(s.mse * 100) << ", \"psnr\": " << json_number(s.psnr)
              << ", \"ssim\": " << json_number(s.ssim) << ", \"lpips\": " << json_number(s.lpips) << "}\n";
}

void print_text(const std::string& path_a, const std::string& path_b, const Scores& s) {
    std::printf("a: %s (%dx%d, %s)\n", path_a.c_str(), s.a.width, s.a.height, s.a.kind.c_str());
    std::printf("b: %s (%dx%d, %s)\n", path_b.c_str(), s.b.width, s.b.height, s.b.kind.c_str());
    std::printf("MSE       %.6g\n", s.mse);
    std::printf("MSE x100  %.6g\n", s.mse * 100);
    if (std::isfinite(s.psnr)) std::printf("PSNR      %.4f dB (data range %g)\n", s.psnr, s.range);
    else std::printf("PSNR      inf (identical)\n");
    if (s.ssim) std::printf("SSIM      %.6f (11x11 Gaussian, sigma 1.5, data range %g)\n", *s.ssim, s.range);
    else std::printf("SSIM      %s\n", s.ssim_note.c_str());
    if (s.lpips) std::printf("LPIPS     %.6f (v0.1, SqueezeNet)\n", *s.lpips);
    else std::printf("LPIPS     %s\n", s.lpips_note.c_str());
}

/// `--pairs FILE`: one pair per line, the two paths separated by a tab (paths may hold spaces);
/// empty lines are skipped. Every pair is checked to exist before any is scored.
std::vector<std::pair<std::string, std::string>> read_pairs(const std::string& file) {
    std::ifstream in_file;
    if (file != "-") {
        // a folder opens as a stream that reads nothing: no scores and exit 0
        if (fs::is_directory(file)) throw std::runtime_error(file + ": a folder, not a --pairs file");
        in_file.open(file);
        if (!in_file) throw std::runtime_error(file + ": cannot open the --pairs file");
    }
    std::istream& in = file == "-" ? std::cin : in_file;
    std::vector<std::pair<std::string, std::string>> pairs;
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        const size_t tab = line.find('\t');
        if (tab == std::string::npos || line.find('\t', tab + 1) != std::string::npos)
            throw std::runtime_error(file + ":" + std::to_string(n) + ": expected two paths separated by one tab");
        pairs.emplace_back(line.substr(0, tab), line.substr(tab + 1));
        for (const std::string& p : {pairs.back().first, pairs.back().second})
            if (!fs::exists(p)) throw std::runtime_error(file + ":" + std::to_string(n) + ": " + p + " not found");
    }
    return pairs;
}

}  // namespace

int run_metrics(const MetricsArgs& args) {
    LpipsOnce lpips(args.vae_dir);
    if (!args.pairs.empty()) {
        if (!args.a.empty() || !args.b.empty())
            throw std::runtime_error("metrics: give two files or --pairs, not both");
        // One JSON object per line, in the file's order; the weights are loaded once.
        for (const auto& [a, b] : read_pairs(args.pairs)) print_json(a, b, score(a, b, lpips));
        return 0;
    }
    if (args.a.empty() || args.b.empty()) throw std::runtime_error("metrics: needs two files a b, or --pairs FILE");
    const Scores s = score(args.a, args.b, lpips);
    if (args.json) print_json(args.a, args.b, s);
    else print_text(args.a, args.b, s);
    return 0;
}

}  // namespace lpt::app
