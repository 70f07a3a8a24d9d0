#include "core/shape.h"
#include "core/warp.h"
#include <algorithm>

namespace lpt {

namespace {
float triangle_area(const TriangleMesh& m, size_t t) {
    const Vec3f& a = m.positions[m.indices[3 * t]];
    const Vec3f& b = m.positions[m.indices[3 * t + 1]];
    const Vec3f& c = m.positions[m.indices[3 * t + 2]];
    return 0.5f * (b - a).cross(c - a).norm();
}
}  // namespace

void Shape::prepare() {
    size_t n = mesh.triangle_count();
    m_cdf.resize(n);
    m_corners.resize(n);
    for (size_t t = 0; t < n; ++t) {
        const uint32_t* idx = &mesh.indices[3 * t];
        Corners& c = m_corners[t];
        for (int k = 0; k < 3; ++k) {
            c.p[k] = mesh.positions[idx[k]];
            if (!mesh.normals.empty()) c.n[k] = mesh.normals[idx[k]];
            if (!mesh.uvs.empty()) c.uv[k] = mesh.uvs[idx[k]];
        }
        c.ng = (c.p[1] - c.p[0]).cross(c.p[2] - c.p[0]).normalized();
    }
    double sum = 0.0;  // double: 270k-triangle meshes lose float precision in the running sum
    for (size_t t = 0; t < n; ++t) {
        sum += triangle_area(mesh, t);
        m_cdf[t] = float(sum);
    }
    m_area = float(sum);
    for (auto& c : m_cdf) c /= m_area;
    if (n) m_cdf.back() = 1.f;
}

PositionSample Shape::sample_position(const Eigen::Vector3f& u) const {
    const uint32_t t = pick_triangle(u.x());
    Vec2f b = sample_uniform_triangle(Vec2f(u.y(), u.z()));
    PositionSample ps;
    const Corners& c = m_corners[t];
    ps.p = (1.f - b.x() - b.y()) * c.p[0] + b.x() * c.p[1] + b.y() * c.p[2];
    ps.n = emission_normal(t, b.x(), b.y());
    ps.pdf_area = 1.f / m_area;
    return ps;
}

Vec3f Shape::emission_normal(uint32_t prim, float u, float v) const {
    const Corners& c = m_corners[prim];
    if (!flat()) {
        Vec3f n = (1.f - u - v) * c.n[0] + u * c.n[1] + v * c.n[2];
        float len = n.norm();
        if (len > 0.f) return n / len;
    }
    return c.ng;
}

SurfaceInteraction Shape::interaction(uint32_t prim, float u, float v, float t) const {
    SurfaceInteraction si;
    const Corners& c = m_corners[prim];
    float w = 1.f - u - v;
    si.p = w * c.p[0] + u * c.p[1] + v * c.p[2];
    si.ng = c.ng;
    si.sh = Frame(emission_normal(prim, u, v));  // the one normal: emitter hits read it from si.sh.n
    if (!mesh.uvs.empty()) si.uv = w * c.uv[0] + u * c.uv[1] + v * c.uv[2];
    si.t = t;
    return si;
}

}  // namespace lpt
