#include "core/light_sampler.h"
#include "core/vectorize.h"
#include "core/envmap.h"
#include "core/spectrum.h"
#include <algorithm>

namespace lpt {

void LightSampler::build(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, LightSampling mode,
                         float scene_radius) {
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

LightSample LightSampler::sample(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes,
                                 const Vec3f& ref, float u_choice, const Vec2f& u_pos) const {
    float u_tri;
    int i = choose(u_choice, &u_tri);
    const Emitter& e = emitters[i];
    LightSample ls = e.kind == EmitterKind::Area
                         ? sample_area_light(shapes[e.shape], ref, Eigen::Vector3f(u_tri, u_pos.x(), u_pos.y()))
                     : e.kind == EmitterKind::EnvMap ? e.envmap->sample(u_pos)
                                                     : sample_constant_light(u_pos);
    ls.emitter = i;
    ls.pdf *= m_pmf[i];
    return ls;
}

void LightBatch::resize(size_t n) {
    for (auto* a : {&rx, &ry,   &rz,  &u_choice, &u_pos0, &u_pos1, &px, &py, &pz, &nx, &ny, &nz, &wx,      &wy,
                    &wz, &dist, &pdf, &ax,       &ay,     &az,     &bx, &by, &bz, &cx, &cy, &cz, &pdf_area})
        if (a->size() < n) a->resize(n);
    if (emitter.size() < n) emitter.resize(n);
    if (scalar.size() < n) scalar.resize(n);
}

namespace {

// The geometry of sample_area_light for flat triangles, lane by lane in the same float
// operations and order as Shape::sample_position + sample_area_light + the pmf product
// (core/vectorize.h). Invalid lanes
// (reference point on the light, light facing away) get pdf 0, as sample() does.
LPT_VECTOR_CLONES
void triangle_light_geometry(LightBatch& b, size_t n) {
    const float* __restrict rx = b.rx.data();
    const float* __restrict ry = b.ry.data();
    const float* __restrict rz = b.rz.data();
    const float* __restrict u0 = b.u_pos0.data();
    const float* __restrict u1 = b.u_pos1.data();
    const float* __restrict ax = b.ax.data();
    const float* __restrict ay = b.ay.data();
    const float* __restrict az = b.az.data();
    const float* __restrict bx = b.bx.data();
    const float* __restrict by = b.by.data();
    const float* __restrict bz = b.bz.data();
    const float* __restrict cx = b.cx.data();
    const float* __restrict cy = b.cy.data();
    const float* __restrict cz = b.cz.data();
    const float* __restrict nx = b.nx.data();
    const float* __restrict ny = b.ny.data();
    const float* __restrict nz = b.nz.data();
    const float* __restrict pdf_area = b.pdf_area.data();
    float* __restrict px = b.px.data();
    float* __restrict py = b.py.data();
    float* __restrict pz = b.pz.data();
    float* __restrict wx = b.wx.data();
    float* __restrict wy = b.wy.data();
    float* __restrict wz = b.wz.data();
    float* __restrict dist = b.dist.data();
    float* __restrict pdf = b.pdf.data();
    // The arrays never overlap (restrict on locals is not enough for GCC's vectoriser).
#pragma GCC ivdep
    for (size_t k = 0; k < n; ++k) {
        const float su = std::sqrt(u0[k]);
        const float b1 = 1.f - su, b2 = u1[k] * su, w = 1.f - b1 - b2;
        const float qx = w * ax[k] + b1 * bx[k] + b2 * cx[k];
        const float qy = w * ay[k] + b1 * by[k] + b2 * cy[k];
        const float qz = w * az[k] + b1 * bz[k] + b2 * cz[k];
        const float dx = qx - rx[k], dy = qy - ry[k], dz = qz - rz[k];
        const float dist2 = dx * dx + dy * dy + dz * dz;
        const float d = std::sqrt(dist2);
        // Masks as 0/1 factors, not selects: GCC will not if-convert a division or square root
        // (they may trap), and a branch keeps the loop scalar. ×1 and +0 are exact.
        const float inv = 1.f / (d + float(dist2 <= 0.f));
        const float ix = dx * inv, iy = dy * inv, iz = dz * inv;
        const float cos_l = -(ix * nx[k] + iy * ny[k] + iz * nz[k]);
        const float ok = float(dist2 > 0.f) * float(cos_l > 0.f);
        px[k] = qx;
        py[k] = qy;
        pz[k] = qz;
        wx[k] = ix;
        wy[k] = iy;
        wz[k] = iz;
        dist[k] = d;
        pdf[k] = ok * (pdf_area[k] * dist2 / (ok * cos_l + (1.f - ok)));
    }
}

}  // namespace

void LightSampler::sample_batch(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, size_t n,
                                LightBatch& b) const {
    // Choices (searches) one entry at a time; the chosen triangle's corners go to the arrays.
    for (size_t k = 0; k < n; ++k) {
        float u_tri;
        const int i = choose(b.u_choice[k], &u_tri);
        b.emitter[k] = i;
        const Emitter& e = emitters[i];
        b.scalar[k] = e.kind != EmitterKind::Area || !shapes[e.shape].flat();
        if (b.scalar[k]) continue;
        const Shape& s = shapes[e.shape];
        const uint32_t t = s.pick_triangle(u_tri);
        const auto& [p0, p1, p2] = s.corner_positions(t);
        const Vec3f& nf = s.face_normal(t);
        b.ax[k] = p0.x();
        b.ay[k] = p0.y();
        b.az[k] = p0.z();
        b.bx[k] = p1.x();
        b.by[k] = p1.y();
        b.bz[k] = p1.z();
        b.cx[k] = p2.x();
        b.cy[k] = p2.y();
        b.cz[k] = p2.z();
        b.nx[k] = nf.x();
        b.ny[k] = nf.y();
        b.nz[k] = nf.z();
        b.pdf_area[k] = 1.f / s.area();
    }
    triangle_light_geometry(b, n);
    for (size_t k = 0; k < n; ++k) {
        if (!b.scalar[k]) {
            b.pdf[k] *= m_pmf[b.emitter[k]];
            continue;
        }
        b.set(k, sample(emitters, shapes, Vec3f(b.rx[k], b.ry[k], b.rz[k]), b.u_choice[k],
                        Vec2f(b.u_pos0[k], b.u_pos1[k])));
    }
}

}  // namespace lpt
