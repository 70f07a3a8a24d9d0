// `latentpt compare`: is a render biased against an independent reference, beyond its noise?
// Means per channel, block ratios with per-block noise, emitter-masked relMSE, and pictures
// (side by side, ratio map). The statistics are core/image_compare.h; docs/validation.md.
#include "apps/commands.h"
#include "apps/render_stack_io.h"
#include "core/image_compare.h"
#include "core/image_io.h"
#include "core/scene.h"
#include "core/scene_loader.h"
#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <stdexcept>

namespace lpt::app {

namespace {

namespace fs = std::filesystem;

std::vector<float> preview(const std::vector<float>& rgb, float exposure) {
    std::vector<float> out(rgb.size());
    const float scale = std::exp2(exposure);
    for (size_t i = 0; i < rgb.size(); ++i) out[i] = linear_to_srgb(std::clamp(rgb[i] * scale, 0.f, 1.f));
    return out;
}

std::vector<float> mean_of(const RenderStack& s) {
    std::vector<float> m(s.renders.front().size(), 0.f);
    for (const auto& r : s.renders)
        for (size_t i = 0; i < m.size(); ++i) m[i] += r[i] / float(s.renders.size());
    return m;
}

/// Images placed left to right with a 4-pixel white gap.
Image side_by_side(const std::vector<std::vector<float>>& panels, int w, int h) {
    const int gap = 4;
    Image out{int(panels.size()) * (w + gap) - gap, h, 3, {}, {"R", "G", "B"}};
    out.data.assign(size_t(out.width) * size_t(h) * 3, 1.f);
    for (size_t i = 0; i < panels.size(); ++i)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c)
                    out.data[(size_t(y) * size_t(out.width) + size_t(int(i) * (w + gap) + x)) * 3 + c] =
                        panels[i][(size_t(y) * size_t(w) + size_t(x)) * 3 + c];
    return out;
}

nlohmann::json to_json(const ImageComparison& c, const CompareArgs& a) {
    nlohmann::json j;
    j["test"] = a.test;
    j["reference"] = a.ref;
    j["test_noise_known"] = c.test_noise_known;
    j["ref_noise_known"] = c.ref_noise_known;
    j["emitter_pixels_masked"] = c.masked_pixels;
    j["mean_test"] = c.test_mean;
    j["mean_ref"] = c.ref_mean;
    j["mean_ratio"] = c.mean_ratio;
    j["mean_ratio_sigma"] = c.mean_ratio_sigma;
    j["rel_mse"] = c.rel_mse;
    j["block_size"] = c.block_size;
    j["z_threshold"] = c.z_threshold;
    j["blocks_flagged"] = c.flagged;
    nlohmann::json blocks = nlohmann::json::array();
    for (const auto& b : c.blocks)
        blocks.push_back({{"x0", b.x0},
                          {"y0", b.y0},
                          {"pixels", b.pixels},
                          {"ratio", b.ratio},
                          {"sigma", b.sigma},
                          {"z", b.z},
                          {"flagged", b.flagged}});
    j["blocks"] = blocks;
    return j;
}

}  // namespace

int run_compare(const CompareArgs& a) {
    if (a.test.empty() || a.ref.empty()) throw std::invalid_argument("compare needs --test and --ref images");
    // a file given twice on a side is no second render: its noise would read as zero
    for (const auto* side : {&a.test, &a.ref})
        for (size_t i = 0; i < side->size(); ++i)
            for (size_t j = i + 1; j < side->size(); ++j)
                if (std::error_code ec; fs::equivalent((*side)[i], (*side)[j], ec))
                    throw std::invalid_argument((*side)[j] + ": given twice to " +
                                                (side == &a.test ? "--test" : "--ref") +
                                                "; the noise estimate needs independent renders (other seeds)");
    RenderStack test = load_stack(a.test, 0);
    RenderStack ref = load_stack(a.ref, test.width);
    if (ref.height != test.height)
        throw std::runtime_error(a.ref.front() + ": height differs from the test's after downsampling");
    std::vector<uint8_t> mask;
    if (!a.scene.empty()) mask = emitter_mask(load_scene(a.scene, a.defines), test.width, test.height);
    const ImageComparison c = compare_renders(test, ref, mask, a.block, a.sigma);

    std::string report = format_comparison(
        c, a.test.front() + (a.test.size() > 1 ? " (+" + std::to_string(a.test.size() - 1) + ")" : ""),
        a.ref.front() + (a.ref.size() > 1 ? " (+" + std::to_string(a.ref.size() - 1) + ")" : ""));
    bool means_ok = true;
    for (double r : c.mean_ratio) means_ok = means_ok && std::abs(r - 1.0) <= a.mean_tolerance;
    const bool blocks_ok = c.flagged == 0 && (c.test_noise_known || c.ref_noise_known);
    report += std::string("verdict: ") + (means_ok && blocks_ok ? "PASS" : "FAIL") + " (means within " +
              std::to_string(a.mean_tolerance * 100.0).substr(0, 4) + " %: " + (means_ok ? "yes" : "no") +
              "; no block beyond " + std::to_string(a.sigma).substr(0, 3) + " sigma: " + (blocks_ok ? "yes" : "no") +
              ")\n";
    std::cout << report << std::flush;

    if (!a.out_dir.empty()) {
        fs::create_directories(a.out_dir);
        const fs::path dir(a.out_dir);
        write_text_atomic((dir / "comparison.txt").string(), report);
        write_text_atomic((dir / "comparison.json").string(), to_json(c, a).dump(1) + "\n");
        const std::vector<float> map = ratio_map(c, test.width, test.height, a.ratio_range);
        write_png_display((dir / "ratio_map.png").string(), Image{test.width, test.height, 3, map, {"R", "G", "B"}});
        write_png_display((dir / "side_by_side.png").string(),
                          side_by_side({preview(mean_of(test), a.exposure), preview(mean_of(ref), a.exposure), map},
                                       test.width, test.height));
        std::cerr << "wrote " << (dir / "comparison.txt").string()
                  << ", comparison.json, ratio_map.png, side_by_side.png "
                  << "(test | reference | block ratio: red = test brighter, blue = darker, saturated at ±"
                  << a.ratio_range * 100 << " %, flagged blocks outlined)\n";
    }
    return a.strict && !(means_ok && blocks_ok) ? 3 : 0;
}

}  // namespace lpt::app
