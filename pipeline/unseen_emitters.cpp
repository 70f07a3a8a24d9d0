#include "pipeline/unseen_emitters.h"
#include "autodiff/tone_curve.h"
#include "integrators/aov.h"
#include "pipeline/reference.h"
#include "pipeline/vae_source.h"
#include "vae/vae.h"
#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>

namespace lpt::pipeline {

std::vector<float> flat_colour_latent(const Vae& vae, const float rgb[3]) {
    // TAESD3's encoder reaches far: the centre latent of a flat 16² (latent) patch is 0.23–0.35
    // from that of a 64² one, whose inner half varies by ~0.013 (white, and (0.8, 0.5, 0.2)). So a
    // 64² patch, and the mean over its inner half.
    const int f = vae.convention().downsample, n = 64, side = n * f, c = vae.convention().channels;
    std::vector<float> image(size_t(side) * side * 3);
    for (size_t i = 0; i < image.size(); ++i) image[i] = rgb[i % 3];
    const std::vector<float> latent = vae.encode(image, side, side);
    std::vector<double> sum(c, 0.0);
    for (int y = n / 4; y < 3 * n / 4; ++y)
        for (int x = n / 4; x < 3 * n / 4; ++x)
            for (int k = 0; k < c; ++k) sum[k] += latent[(size_t(y) * n + x) * c + k];
    std::vector<float> mean(c);
    for (int k = 0; k < c; ++k) mean[k] = float(sum[k] / double(n * n / 4));
    return mean;
}

namespace {

/// What a camera ray that hits nothing brings back in RGB: the environment's radiance (an
/// environment map's mean), black without one.
Eigen::Array3f environment_radiance(const Scene& scene) {
    return scene.environment >= 0 ? scene.emitters[scene.environment].radiance_rgb : Eigen::Array3f::Zero();
}

}  // namespace

UnseenEmitters::UnseenEmitters(const FitFolder& fit, const Scene* training_view) {
    if (!vae_present(fit.vae)) return;
    const Scene& scene = *fit.scene;
    const Scene& seen_from = training_view ? *training_view : scene;
    if (seen_from.shapes.size() != scene.shapes.size())
        throw std::runtime_error(fit.dir + ": the -D overrides change the scene's shapes (" +
                                 std::to_string(scene.shapes.size()) + " against " +
                                 std::to_string(seen_from.shapes.size()) + " as fitted)");
    std::vector<int> candidates;  // the area emitters' shapes, then -1: rays that hit nothing
    std::vector<Eigen::Array3f> radiance;
    for (const Emitter& e : scene.emitters)
        if (!e.is_environment() && e.shape >= 0) {
            candidates.push_back(e.shape);
            radiance.push_back(e.radiance_rgb);
        }
    candidates.push_back(-1);
    radiance.push_back(environment_radiance(scene));
    // At least 256 rays across the narrower side: on a latent of a few pixels, 8 × 8 per pixel
    // could step over a gap between a wall and the view's edge that the render's samples find.
    const int w = fit.latent_width, h = fit.latent_height, rays = std::max(8, (255 + std::min(w, h)) / std::min(w, h));
    const std::vector<float> seen = render_shape_coverage(seen_from, w, h, candidates, rays);
    std::unique_ptr<Vae> vae;
    for (size_t s = 0; s < candidates.size(); ++s) {
        bool any = false;
        for (size_t p = 0; p < size_t(w) * h && !any; ++p) any = seen[p * candidates.size() + s] > 0.f;
        if (any) continue;
        float rgb[3];
        for (int k = 0; k < 3; ++k) rgb[k] = display_value(radiance[s][k], fit.ref_tone);
        if (!vae) vae = open_vae(fit.vae);
        std::vector<float> look = flat_colour_latent(*vae, rgb);
        if (candidates[s] < 0) {
            const bool black = rgb[0] == 0.f && rgb[1] == 0.f && rgb[2] == 0.f;  // no environment
            const float zero[3] = {0.f, 0.f, 0.f};
            m_black = black ? look : flat_colour_latent(*vae, zero);
            m_environment = std::move(look);
        } else {
            m_shapes.push_back(candidates[s]);
            m_looks.push_back(std::move(look));
        }
    }
}

void UnseenEmitters::show(LatentTerms<kLatentChannels>& terms, ToneCurve tone, size_t shapes, bool on) const {
    terms.look_of_shape.clear();
    terms.look_of_nothing = -1;
    terms.look_of_black = -1;
    terms.looks.clear();
    if (!on || (m_shapes.empty() && !m_environment)) return;
    auto add = [&](const std::vector<float>& look) {
        Spectrum<kLatentChannels> x;
        for (int k = 0; k < kLatentChannels; ++k) x[k] = tone_inverse(tone, look[k]);
        terms.looks.push_back(x);
        return int(terms.looks.size()) - 1;
    };
    terms.look_of_shape.assign(shapes, -1);
    for (size_t s = 0; s < m_shapes.size(); ++s) terms.look_of_shape[m_shapes[s]] = add(m_looks[s]);
    if (m_environment) terms.look_of_nothing = add(*m_environment);
    if (m_black) terms.look_of_black = add(*m_black);
}

}  // namespace lpt::pipeline
