#include "core/image_compare.h"
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace lpt {

namespace {

/// Per-pixel mean over the stack, and the variance of that mean (0 when K = 1), per channel.
struct StackMoments {
    std::vector<double> mean;      ///< w·h·3
    std::vector<double> var_mean;  ///< w·h·3, variance of `mean` per channel
    std::vector<double> var_grey;  ///< w·h, variance of the channel average (channels correlate)
};

StackMoments moments(const RenderStack& s) {
    const size_t n = size_t(s.width) * size_t(s.height);
    const size_t k = s.renders.size();
    StackMoments m;
    m.mean.assign(n * 3, 0.0);
    m.var_mean.assign(n * 3, 0.0);
    m.var_grey.assign(n, 0.0);
    for (const auto& r : s.renders)
        for (size_t i = 0; i < n * 3; ++i) m.mean[i] += r[i] / double(k);
    if (k < 2) return m;
    // Unbiased sample variance of one render, divided by K for the variance of the mean.
    const double scale = 1.0 / (double(k - 1) * double(k));
    for (const auto& r : s.renders) {
        for (size_t p = 0; p < n; ++p) {
            double grey_dev = 0;
            for (int c = 0; c < 3; ++c) {
                double d = r[p * 3 + c] - m.mean[p * 3 + c];
                m.var_mean[p * 3 + c] += d * d * scale;
                grey_dev += d / 3.0;
            }
            m.var_grey[p] += grey_dev * grey_dev * scale;
        }
    }
    return m;
}

void check_stack(const RenderStack& s, const char* name) {
    if (s.renders.empty()) throw std::invalid_argument(std::string(name) + ": no renders given");
    const size_t n = size_t(s.width) * size_t(s.height) * 3;
    for (const auto& r : s.renders)
        if (r.size() != n) throw std::invalid_argument(std::string(name) + ": renders differ in size");
}

/// Whether the renders' spread estimates their noise: two or more, not all equal (equal renders
/// estimate zero noise, and a zero sigma flags no block: one file given twice passed --strict
/// with blocks 17 % off; a noise-free set-up gives equal renders too, and its noise is unknown).
bool noise_known(const RenderStack& s) {
    for (size_t i = 1; i < s.renders.size(); ++i)
        if (s.renders[i] != s.renders[0]) return true;
    return false;
}

/// Ratio a/b of two independent noisy means and its 1σ from first-order error propagation.
void ratio_with_noise(double a, double var_a, double b, double var_b, double& ratio, double& sigma) {
    ratio = b != 0 ? a / b : (a == 0 ? 1.0 : INFINITY);
    sigma = (a != 0 && b != 0) ? std::abs(ratio) * std::sqrt(var_a / (a * a) + var_b / (b * b)) : 0.0;
}

/// One block's channel-average ratio with its noise; masked pixels left out.
BlockComparison compare_block(const StackMoments& t, const StackMoments& r, const std::vector<uint8_t>& emitter_mask,
                              int w, int h, int x0, int y0, int block_size, double z_threshold) {
    BlockComparison b;
    b.x0 = x0;
    b.y0 = y0;
    b.width = std::min(block_size, w - b.x0);
    b.height = std::min(block_size, h - b.y0);
    double vt = 0, vr = 0;
    for (int y = b.y0; y < b.y0 + b.height; ++y) {
        for (int x = b.x0; x < b.x0 + b.width; ++x) {
            const size_t p = size_t(y) * size_t(w) + size_t(x);
            if (!emitter_mask.empty() && emitter_mask[p] != 0) continue;
            ++b.pixels;
            for (int ch = 0; ch < 3; ++ch) {
                b.test_mean += t.mean[p * 3 + ch] / 3.0;
                b.ref_mean += r.mean[p * 3 + ch] / 3.0;
            }
            vt += t.var_grey[p];
            vr += r.var_grey[p];
        }
    }
    if (b.pixels == 0) return b;
    const double ib = 1.0 / double(b.pixels);
    b.test_mean *= ib;
    b.ref_mean *= ib;
    ratio_with_noise(b.test_mean, vt * ib * ib, b.ref_mean, vr * ib * ib, b.ratio, b.sigma);
    b.z = b.sigma > 0 ? (b.ratio - 1.0) / b.sigma : 0.0;
    // With no noise known on either side every difference would look significant: nothing is
    // flagged, and the report says why.
    b.flagged = b.sigma > 0 && std::abs(b.z) > z_threshold;
    return b;
}

}  // namespace

ImageComparison compare_renders(const RenderStack& test, const RenderStack& ref,
                                const std::vector<uint8_t>& emitter_mask, int block_size, double z_threshold) {
    check_stack(test, "test");
    check_stack(ref, "reference");
    if (test.width != ref.width || test.height != ref.height)
        throw std::invalid_argument("test is " + std::to_string(test.width) + "x" + std::to_string(test.height) +
                                    ", reference " + std::to_string(ref.width) + "x" + std::to_string(ref.height));
    if (block_size < 1) throw std::invalid_argument("block size must be >= 1");
    const int w = test.width, h = test.height;
    const size_t n = size_t(w) * size_t(h);
    if (!emitter_mask.empty() && emitter_mask.size() != n)
        throw std::invalid_argument("emitter mask size differs from the images");
    const StackMoments t = moments(test), r = moments(ref);
    auto masked = [&](size_t p) { return !emitter_mask.empty() && emitter_mask[p] != 0; };

    ImageComparison c;
    c.block_size = block_size;
    c.z_threshold = z_threshold;
    c.test_noise_known = noise_known(test);
    c.ref_noise_known = noise_known(ref);

    // Whole-image channel means (eq. (1)) and relMSE (eq. (3)).
    std::array<double, 3> var_t{}, var_r{};
    size_t used = 0;
    double rel = 0;
    for (size_t p = 0; p < n; ++p) {
        if (masked(p)) {
            ++c.masked_pixels;
            continue;
        }
        ++used;
        for (int ch = 0; ch < 3; ++ch) {
            const double a = t.mean[p * 3 + ch], b = r.mean[p * 3 + ch];
            c.test_mean[ch] += a;
            c.ref_mean[ch] += b;
            var_t[ch] += t.var_mean[p * 3 + ch];
            var_r[ch] += r.var_mean[p * 3 + ch];
            rel += (a - b) * (a - b) / (b * b + 0.01);
        }
    }
    if (used == 0) throw std::invalid_argument("every pixel is masked");
    const double inv = 1.0 / double(used);
    for (int ch = 0; ch < 3; ++ch) {
        c.test_mean[ch] *= inv;
        c.ref_mean[ch] *= inv;
        ratio_with_noise(c.test_mean[ch], var_t[ch] * inv * inv, c.ref_mean[ch], var_r[ch] * inv * inv,
                         c.mean_ratio[ch], c.mean_ratio_sigma[ch]);
    }
    c.rel_mse = rel / double(used * 3);

    // Block ratios of the channel average with their noise (eq. (2)).
    c.blocks_x = (w + block_size - 1) / block_size;
    c.blocks_y = (h + block_size - 1) / block_size;
    for (int by = 0; by < c.blocks_y; ++by)
        for (int bx = 0; bx < c.blocks_x; ++bx) {
            c.blocks.push_back(
                compare_block(t, r, emitter_mask, w, h, bx * block_size, by * block_size, block_size, z_threshold));
            c.flagged += c.blocks.back().flagged ? 1 : 0;
        }
    return c;
}

std::string format_comparison(const ImageComparison& c, const std::string& test_name, const std::string& ref_name) {
    std::ostringstream o;
    char buf[256];
    o << "test:      " << test_name << (c.test_noise_known ? "" : "  (one render: its noise is not estimated)") << "\n";
    o << "reference: " << ref_name << (c.ref_noise_known ? "" : "  (one render: its noise is not estimated)") << "\n";
    o << "emitter pixels left out: " << c.masked_pixels << "\n";
    const char* names[3] = {"R", "G", "B"};
    for (int ch = 0; ch < 3; ++ch) {
        std::snprintf(buf, sizeof buf, "mean %s: test %.6g  ref %.6g  ratio %.4f ± %.4f (%+.2f %%)\n", names[ch],
                      c.test_mean[ch], c.ref_mean[ch], c.mean_ratio[ch], c.mean_ratio_sigma[ch],
                      100.0 * (c.mean_ratio[ch] - 1.0));
        o << buf;
    }
    std::snprintf(buf, sizeof buf, "relMSE (emitters masked): %.6g\n", c.rel_mse);
    o << buf;
    std::vector<double> ratios, zs;
    int brighter = 0, darker = 0, used = 0;
    for (const auto& b : c.blocks) {
        if (b.pixels == 0) continue;
        ++used;
        ratios.push_back(b.ratio);
        zs.push_back(b.z);
        brighter += b.ratio > 1.0;
        darker += b.ratio < 1.0;
    }
    std::sort(ratios.begin(), ratios.end());
    double median = ratios.empty() ? 1.0 : ratios[ratios.size() / 2];
    double z_rms = 0;
    for (double z : zs) z_rms += z * z;
    z_rms = zs.empty() ? 0 : std::sqrt(z_rms / double(zs.size()));
    std::snprintf(buf, sizeof buf,
                  "%dx%d blocks: %d used, test brighter in %d, darker in %d; median ratio %.4f, min %.4f, max %.4f; "
                  "rms z %.2f (1 if the differences are noise alone)\n",
                  c.block_size, c.block_size, used, brighter, darker, median, ratios.empty() ? 1.0 : ratios.front(),
                  ratios.empty() ? 1.0 : ratios.back(), z_rms);
    o << buf;
    if (!c.test_noise_known && !c.ref_noise_known) {
        o << "no noise estimate on either side: blocks are not flagged (give >= 2 renders per side)\n";
        return o.str();
    }
    std::snprintf(buf, sizeof buf, "blocks beyond %.1f sigma: %d\n", c.z_threshold, c.flagged);
    o << buf;
    for (const auto& b : c.blocks) {
        if (!b.flagged) continue;
        std::snprintf(buf, sizeof buf, "  block x %4d..%-4d y %4d..%-4d ratio %.4f ± %.4f  z %+.1f\n", b.x0,
                      b.x0 + b.width - 1, b.y0, b.y0 + b.height - 1, b.ratio, b.sigma, b.z);
        o << buf;
    }
    return o.str();
}

std::vector<float> ratio_map(const ImageComparison& c, int width, int height, double range) {
    std::vector<float> img(size_t(width) * size_t(height) * 3, 0.5f);
    for (const auto& b : c.blocks) {
        // Blocks with no unmasked pixel stay grey.
        const double s = b.pixels > 0 ? std::clamp((b.ratio - 1.0) / range, -1.0, 1.0) : 0.0;
        float rgb[3] = {0.5f, 0.5f, 0.5f};
        if (b.pixels > 0) {
            rgb[0] = float(s < 0 ? 1.0 + s : 1.0);
            rgb[1] = float(1.0 - std::abs(s));
            rgb[2] = float(s > 0 ? 1.0 - s : 1.0);
        }
        for (int y = b.y0; y < b.y0 + b.height && y < height; ++y) {
            for (int x = b.x0; x < b.x0 + b.width && x < width; ++x) {
                const bool edge =
                    b.flagged && (x == b.x0 || y == b.y0 || x == b.x0 + b.width - 1 || y == b.y0 + b.height - 1);
                for (int ch = 0; ch < 3; ++ch)
                    img[(size_t(y) * size_t(width) + size_t(x)) * 3 + ch] = edge ? 0.f : rgb[ch];
            }
        }
    }
    return img;
}

}  // namespace lpt
