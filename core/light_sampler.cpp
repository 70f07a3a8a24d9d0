#include "core/light_sampler.h"
#include "core/envmap.h"
#include "core/spectrum.h"
#include <algorithm>

namespace lpt {

void LightSampler::build(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, LightSampling mode, float scene_radius) {
    m_pmf.assign(emitters.size(), 0.f);
    m_cdf.assign(emitters.size(), 0.f);
    if (emitters.empty()) return;
    // The environment's "area" is the scene's bounding sphere, its flux ~ L pi 4 pi r^2.
    double total = 0.0;
    for (size_t i = 0; i < emitters.size(); ++i) {
        const Emitter& e = emitters[i];
        float area = e.kind == EmitterKind::Area ? shapes[e.shape].area() : 4.f * kPi * scene_radius * scene_radius;
        float w = 1.f;
        if (mode == LightSampling::Area) w = area;
        if (mode == LightSampling::Power) w = std::abs(luminance(e.radiance_rgb)) * area * kPi;
        m_pmf[i] = std::max(w, 0.f);
        total += m_pmf[i];
    }
    if (total <= 0.0) {  // all-black lights: fall back to uniform so pdfs stay defined
        std::fill(m_pmf.begin(), m_pmf.end(), 1.f);
        total = double(m_pmf.size());
    }
    double acc = 0.0;
    for (size_t i = 0; i < m_pmf.size(); ++i) {
        m_pmf[i] = float(m_pmf[i] / total);
        acc += m_pmf[i];
        m_cdf[i] = float(acc);
    }
    m_cdf.back() = 1.f;
}

int LightSampler::choose(float u, float* u_reuse) const {
    if (m_pmf.size() == 1) {  // the common single-light scene: no search
        if (u_reuse) *u_reuse = u;
        return 0;
    }
    int i = int(std::upper_bound(m_cdf.begin(), m_cdf.end(), u) - m_cdf.begin());
    i = std::min(i, int(m_cdf.size()) - 1);
    while (m_pmf[i] == 0.f && i > 0) --i;  // never return a zero-probability light
    float lo = i > 0 ? m_cdf[i - 1] : 0.f;
    if (u_reuse) *u_reuse = std::clamp((u - lo) / m_pmf[i], 0.f, 0x1.fffffep-1f);
    return i;
}

LightSample LightSampler::sample(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, const Vec3f& ref,
                                 float u_choice, const Vec2f& u_pos) const {
    float u_tri;
    int i = choose(u_choice, &u_tri);
    const Emitter& e = emitters[i];
    LightSample ls = e.kind == EmitterKind::Area     ? sample_area_light(shapes[e.shape], ref, Eigen::Vector3f(u_tri, u_pos.x(), u_pos.y()))
                     : e.kind == EmitterKind::EnvMap ? e.envmap->sample(u_pos)
                                                     : sample_constant_light(u_pos);
    ls.emitter = i;
    ls.pdf *= m_pmf[i];
    return ls;
}

}  // namespace lpt
