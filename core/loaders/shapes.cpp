// Mitsuba's analytic shapes as triangle meshes in object space: rectangle, cube, sphere.
// All wind counter-clockwise seen from outside, so edge cross products point along the normals.
#include "core/mesh.h"
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lpt {

TriangleMesh make_rectangle() {
    TriangleMesh m;
    m.positions = {Vec3f(-1, -1, 0), Vec3f(1, -1, 0), Vec3f(1, 1, 0), Vec3f(-1, 1, 0)};
    m.normals.assign(4, Vec3f::UnitZ());
    m.uvs = {Vec2f(0, 0), Vec2f(1, 0), Vec2f(1, 1), Vec2f(0, 1)};
    m.indices = {0, 1, 2, 0, 2, 3};
    return m;
}

TriangleMesh make_cube() {
    TriangleMesh m;
    // Per face: outward normal n and in-plane axes (u, v) with u x v = n, so corners listed as
    // (-,-), (+,-), (+,+), (-,+) in (u, v) run counter-clockwise seen from outside. Four vertices
    // per face (24 total) because a corner's normal differs between its three faces.
    for (int axis = 0; axis < 3; ++axis) {
        for (float sign : {1.f, -1.f}) {
            Vec3f n = Vec3f::Zero();
            n[axis] = sign;
            Vec3f u = Vec3f::Zero();
            u[(axis + 1) % 3] = sign;
            Vec3f v = n.cross(u);
            uint32_t base = uint32_t(m.positions.size());
            const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
            for (const auto& c : corners) {
                m.positions.push_back(n + c[0] * u + c[1] * v);
                m.normals.push_back(n);
                m.uvs.emplace_back(0.5f * (c[0] + 1), 0.5f * (c[1] + 1));
            }
            m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
        }
    }
    return m;
}

TriangleMesh make_sphere(int rings, int segments) {
    if (rings < 2 || segments < 3)
        throw std::invalid_argument("make_sphere needs rings >= 2 and segments >= 3, got " + std::to_string(rings) +
                                    " and " + std::to_string(segments));
    TriangleMesh m;
    // Grid of (rings + 1) x (segments + 1) vertices: the seam column is duplicated so u runs to 1
    // without wrapping, and each pole is repeated per segment so u there is the segment's middle.
    // theta is measured from +z, so the top band's row 0 is the north pole.
    const uint32_t row = uint32_t(segments) + 1;
    for (int i = 0; i <= rings; ++i) {
        float theta = kPi * float(i) / float(rings);
        for (int j = 0; j <= segments; ++j) {
            bool pole = i == 0 || i == rings;
            // (The pole's seam copy is never referenced; clamping keeps its u in [0, 1] anyway.)
            float u = std::min((float(j) + (pole ? 0.5f : 0.f)) / float(segments), 1.f);
            float phi = 2.f * kPi * u;
            Vec3f p = pole ? Vec3f(0, 0, i == 0 ? 1.f : -1.f)
                           : Vec3f(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            m.positions.push_back(p);
            m.normals.push_back(p);
            m.uvs.emplace_back(u, float(i) / float(rings));
        }
    }
    // In a grid cell a=(i,j), b=(i+1,j), c=(i+1,j+1), d=(i,j+1), b-a runs along +theta and d-a
    // along +phi, and theta x phi is the outward radial direction: (a,b,c) and (a,c,d) face out.
    // At the poles the cell collapses to one triangle; the pole vertex's zero-length edge is
    // skipped rather than emitted as a sliver.
    for (int i = 0; i < rings; ++i) {
        for (int j = 0; j < segments; ++j) {
            uint32_t a = uint32_t(i) * row + uint32_t(j), b = a + row, c = b + 1, d = a + 1;
            if (i != rings - 1) m.indices.insert(m.indices.end(), {a, b, c});
            if (i != 0) m.indices.insert(m.indices.end(), {a, c, d});
        }
    }
    return m;
}

}  // namespace lpt
