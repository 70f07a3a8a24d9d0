#include "pipeline/emitter_refiner.h"
#include "integrators/aov.h"
#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace lpt::pipeline {

void remove_emitter_refiner(const std::string& dir) {
    namespace fs = std::filesystem;
    for (const char* name : {kEmitterRefinerFile, kEmitterRefinerCheckpoint, kEmitterRefinerLoss})
        fs::remove(fs::path(dir) / name);
    fs::remove((fs::path(dir) / kEmitterRefinerCheckpoint).replace_extension(".json"));
}

std::vector<float> dilate_mask(const std::vector<float>& mask, int w, int h, int radius) {
    std::vector<float> out(size_t(w) * h, 0.f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (mask[size_t(y) * w + x] == 0.f) continue;
            for (int v = std::max(0, y - radius); v <= std::min(h - 1, y + radius); ++v)
                for (int u = std::max(0, x - radius); u <= std::min(w - 1, x + radius); ++u)
                    out[size_t(v) * w + u] = 1.f;
        }
    return out;
}

std::vector<float> emitter_coverage(const Scene& scene, int w, int h) {
    return render_emitter_cells(scene, w, h, kEmitterMaskCells);
}

std::vector<float> emitter_mask(const std::vector<float>& coverage, const std::vector<float>& training, int w, int h,
                                int dilation) {
    const size_t k = coverage.size() / (size_t(w) * h);
    const bool compare = training.size() == coverage.size();
    std::vector<float> changed(size_t(w) * h, 0.f);
    for (size_t p = 0; p < changed.size(); ++p)
        for (size_t c = p * k; c < (p + 1) * k; ++c)
            if (compare ? coverage[c] != training[c] : coverage[c] > 0.f) changed[p] = 1.f;
    return dilate_mask(changed, w, h, dilation);
}

std::vector<float> take_near_emitters(std::vector<float> refined, const std::vector<float>& emitter_refined,
                                      const std::vector<float>& mask, int channels) {
    for (size_t p = 0; p < mask.size(); ++p)
        if (mask[p] != 0.f)
            std::copy_n(emitter_refined.begin() + p * channels, channels, refined.begin() + p * channels);
    return refined;
}

void check_emitter_refiner_inputs(const RefinerConfig& main, const RefinerConfig& emitters, const std::string& path) {
    if (main.terms != emitters.terms)
        throw std::runtime_error(path + ": the emitter refiner reads " +
                                 (emitters.terms ? "the transport terms" : "the latent") + " and refiner.pt " +
                                 (main.terms ? "the transport terms" : "the latent") +
                                 ": train both with the same --inputs");
}

std::vector<float> refine_with_emitters(const Refiner& main, const Refiner* emitters, const Scene& scene,
                                        const RefinerInput& in, const std::vector<float>& training_coverage) {
    std::vector<float> refined = main.refine(in);
    if (!emitters) return refined;
    const std::vector<float> mask =
        emitter_mask(emitter_coverage(scene, in.width, in.height), training_coverage, in.width, in.height);
    if (std::none_of(mask.begin(), mask.end(), [](float m) { return m != 0.f; })) return refined;
    RefinerInput own = in;
    const int cells = emitters->config().emitter_cells;
    if (cells != main.config().emitter_cells)
        own.emitter = cells ? render_emitter_cells(scene, in.width, in.height, cells) : std::vector<float>{};
    return take_near_emitters(std::move(refined), emitters->refine(own), mask, main.config().latent_channels);
}

}  // namespace lpt::pipeline
