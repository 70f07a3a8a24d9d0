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
    m_face_normals.resize(n);
    for (size_t t = 0; t < n; ++t) {
        const uint32_t* idx = &mesh.indices[3 * t];
        m_face_normals[t] = (mesh.positions[idx[1]] - mesh.positions[idx[0]])
                                .cross(mesh.positions[idx[2]] - mesh.positions[idx[0]])
                                .normalized();
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
    const uint32_t* idx = &mesh.indices[3 * t];
    const Vec3f &p0 = mesh.positions[idx[0]], &p1 = mesh.positions[idx[1]], &p2 = mesh.positions[idx[2]];
    ps.p = (1.f - b.x() - b.y()) * p0 + b.x() * p1 + b.y() * p2;
    ps.n = emission_normal(t, b.x(), b.y());
    ps.pdf_area = 1.f / m_area;
    return ps;
}

Vec3f Shape::emission_normal(uint32_t prim, float u, float v) const {
    const uint32_t* idx = &mesh.indices[3 * prim];
    if (!flat()) {
        Vec3f n = (1.f - u - v) * mesh.normals[idx[0]] + u * mesh.normals[idx[1]] + v * mesh.normals[idx[2]];
        float len = n.norm();
        if (len > 0.f) return n / len;
    }
    return m_face_normals[prim];
}

SurfaceInteraction Shape::interaction(uint32_t prim, float u, float v, float t) const {
    SurfaceInteraction si;
    const uint32_t* idx = &mesh.indices[3 * prim];
    const Vec3f &p0 = mesh.positions[idx[0]], &p1 = mesh.positions[idx[1]], &p2 = mesh.positions[idx[2]];
    float w = 1.f - u - v;
    si.p = w * p0 + u * p1 + v * p2;
    si.ng = m_face_normals[prim];
    Vec3f ns = si.ng;
    if (!face_normals && !mesh.normals.empty()) {
        Vec3f n = w * mesh.normals[idx[0]] + u * mesh.normals[idx[1]] + v * mesh.normals[idx[2]];
        float len = n.norm();
        if (len > 0.f) ns = n / len;
    }
    si.sh = Frame(ns);
    if (!mesh.uvs.empty()) si.uv = w * mesh.uvs[idx[0]] + u * mesh.uvs[idx[1]] + v * mesh.uvs[idx[2]];
    si.t = t;
    return si;
}

}  // namespace lpt
