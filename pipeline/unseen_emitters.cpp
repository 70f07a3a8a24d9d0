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
    // At least 256 rays across the narrower side: on a latent of a few pixels, 8 × 8 per pixel
    // could step over a gap between a wall and the view's edge that the render's samples find.
    const int w = fit.latent_width, h = fit.latent_height, rays = std::max(8, (255 + std::min(w, h)) / std::min(w, h));
    const CameraSights sights = camera_sights(seen_from, SceneSpectra<3>::from_description(seen_from), w, h, rays);
    std::unique_ptr<Vae> vae;
    auto look_of = [&](const Eigen::Array3f& radiance) {
        float rgb[3];
        for (int k = 0; k < 3; ++k) rgb[k] = display_value(radiance[k], fit.ref_tone);
        if (!vae) vae = open_vae(fit.vae);
        return flat_colour_latent(*vae, rgb);
    };
    // an emitter seen only from behind was never fitted as it looks: its look is its emitting side's
    for (const Emitter& e : scene.emitters)
        if (!e.is_environment() && e.shape >= 0 && !sights.front_of[size_t(e.shape)]) {
            m_shapes.push_back(e.shape);
            m_looks.push_back(look_of(e.radiance_rgb));
        }
    if (!sights.nothing) m_environment = look_of(environment_radiance(scene));
    // b̃ was fitted to what paths that end in the background brought back; a view whose black
    // backs are worth less than a latent pixel, or 1/4096 of the view (smooth silhouettes' stray
    // rays grow with the view: cbox-specular's, 14 rays of ~10⁶, are 0.22 pixels at 128²),
    // fitted it to none, and RGB shows them black, whatever the environment.
    const float worth = std::max(1.f, float(w) * float(h) / 4096.f);
    if (sights.black_back_pixels < worth) {
        const bool environment_black = m_environment && (environment_radiance(scene) == 0.f).all();
        m_black = environment_black ? *m_environment : look_of(Eigen::Array3f::Zero());
    }
}

std::string UnseenEmitters::key() const {
    std::string key;
    auto add = [&key](const std::string& what) { key += (key.empty() ? "" : " ") + what; };
    for (int shape : m_shapes) add("shape " + std::to_string(shape));
    if (m_environment) add("the environment");
    if (m_black) add("black backs");
    return key;
}

void UnseenEmitters::show(LatentTerms<kLatentChannels>& terms, ToneCurve tone, size_t shapes, bool on) const {
    terms.look_of_shape.clear();
    terms.look_of_nothing = -1;
    terms.look_of_black = -1;
    terms.looks.clear();
    if (!on || (m_shapes.empty() && !m_environment && !m_black)) return;
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
