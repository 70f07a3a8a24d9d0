#include "pipeline/unseen_emitters.h"
#include "integrators/aov.h"
#include "pipeline/reference.h"
#include "pipeline/vae_source.h"
#include "vae/vae.h"
#include <memory>
#include <stdexcept>

namespace lpt::pipeline {

std::vector<float> flat_colour_latent(const Vae& vae, const float rgb[3]) {
    // 16 latent pixels a side: the centre is ≥ 8 from every border, past the encoder's reach of
    // the zero padding (TAESD3's encoding of a flat image is flat there to float precision).
    const int f = vae.convention().downsample, side = 16 * f, c = vae.convention().channels;
    std::vector<float> image(size_t(side) * side * 3);
    for (size_t i = 0; i < image.size(); ++i) image[i] = rgb[i % 3];
    const std::vector<float> latent = vae.encode(image, side, side);
    const size_t centre = (size_t(8) * 16 + 8) * c;
    return std::vector<float>(latent.begin() + centre, latent.begin() + centre + c);
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
