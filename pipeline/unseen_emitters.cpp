#include "pipeline/unseen_emitters.h"
#include "integrators/aov.h"
#include "pipeline/reference.h"
#include "pipeline/vae_source.h"
#include "vae/vae.h"
#include <memory>
#include <stdexcept>

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

UnseenEmitters::UnseenEmitters(const FitFolder& fit) {
    if (!vae_present(fit.vae)) return;
    const Scene& scene = *fit.scene;
    std::vector<int> emitters;
    for (const Emitter& e : scene.emitters)
        if (!e.is_environment() && e.shape >= 0) emitters.push_back(e.shape);
    if (emitters.empty()) return;
    const int w = fit.latent_width, h = fit.latent_height;
    const std::vector<float> seen = render_shape_coverage(scene, w, h, emitters);
    std::unique_ptr<Vae> vae;
    for (size_t s = 0; s < emitters.size(); ++s) {
        bool any = false;
        for (size_t p = 0; p < size_t(w) * h && !any; ++p) any = seen[p * emitters.size() + s] > 0.f;
        if (any) continue;
        const Emitter& e = scene.emitters[scene.shapes[emitters[s]].emitter];
        float rgb[3];
        for (int k = 0; k < 3; ++k) rgb[k] = display_value(e.radiance_rgb[k], fit.ref_tone);
        if (!vae) vae = open_vae(fit.vae);
        m_shapes.push_back(emitters[s]);
        m_looks.push_back(flat_colour_latent(*vae, rgb));
    }
}

std::vector<float> UnseenEmitters::coverage(const Scene& scene, int w, int h) const {
    return render_shape_coverage(scene, w, h, m_shapes);
}

void UnseenEmitters::paint(const std::vector<float>& coverage, int w, int h, std::vector<float>& latent) const {
    const size_t n = m_shapes.size(), pixels = size_t(w) * h;
    if (n == 0) return;
    const size_t c = m_looks[0].size();
    if (latent.size() != pixels * c || coverage.size() != pixels * n)
        throw std::invalid_argument("UnseenEmitters::paint: latent or coverage of another size");
    for (size_t p = 0; p < pixels; ++p)
        for (size_t s = 0; s < n; ++s) {
            const float a = coverage[p * n + s];
            if (a <= 0.f) continue;
            for (size_t k = 0; k < c; ++k) latent[p * c + k] = (1.f - a) * latent[p * c + k] + a * m_looks[s][k];
        }
}

}  // namespace lpt::pipeline
