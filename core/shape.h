// Shape: a triangle mesh in world space with an id, a material and (optionally) an area
// emitter. Analytic shapes are tessellated at load time (core/loaders/shapes.cpp), so one
// code path intersects, samples and differentiates every shape.
#pragma once
#include "core/geometry.h"
#include "core/mesh.h"
#include <algorithm>
#include <array>
#include <string>
#include <vector>

namespace lpt {

struct SurfaceInteraction {
    Vec3f p = Vec3f::Zero();
    Vec3f ng = Vec3f::UnitZ();  ///< geometric normal (unit), winding-defined side
    Frame sh;                   ///< shading frame around the interpolated normal
    Vec2f uv = Vec2f::Zero();
    float t = kInf;
    int shape = -1;
    bool valid() const { return shape >= 0; }
};

struct PositionSample {
    Vec3f p, n;      ///< point and its (shading) normal: the side an area light emits to
    float pdf_area;  ///< density per unit area
};

class Shape {
public:
    std::string id;
    TriangleMesh mesh;          ///< world space
    bool face_normals = false;  ///< ignore vertex normals (Mitsuba `face_normals`)
    int material = -1;          ///< index into Scene::materials
    int emitter = -1;           ///< index into Scene::emitters, -1 if not emissive

    /// Computes area, the triangle distribution and the per-triangle corner records that hits
    /// read; call after the mesh changes (Scene::build does), or hits read the old mesh.
    void prepare();
    float area() const { return m_area; }
    /// Uniform by area: u.x() picks the triangle (then is reused), u.y()/u.z() the point.
    PositionSample sample_position(const Eigen::Vector3f& u) const;
    /// sample_position's triangle for u.x().
    uint32_t pick_triangle(float u) const {
        size_t t = 0;
        if (m_cdf.size() <= 8) {  // typical emitters (a quad: two): a count, no mispredicted search steps
            for (float c : m_cdf) t += size_t(c <= u);
        } else {
            t = size_t(std::upper_bound(m_cdf.begin(), m_cdf.end(), u) - m_cdf.begin());
        }
        return uint32_t(std::min(t, m_cdf.size() - 1));
    }
    /// Whether emission_normal is the face normal (no interpolated vertex normals).
    bool flat() const { return face_normals || mesh.normals.empty(); }
    const Vec3f& face_normal(uint32_t prim) const { return m_corners[prim].ng; }
    /// The triangle's three corner positions, from the record a hit reads (no index lookups).
    const std::array<Vec3f, 3>& corner_positions(uint32_t prim) const { return m_corners[prim].p; }
    /// Hit record from Embree's (primID, u, v, t): barycentrics p = (1-u-v) p0 + u p1 + v p2.
    SurfaceInteraction interaction(uint32_t prim, float u, float v, float t) const;
    /// Normal used for emission side and light pdfs at a hit (matches sample_position).
    Vec3f emission_normal(uint32_t prim, float u, float v) const;

private:
    /// One triangle's corners, copied out of the mesh by prepare(): a hit reads one record instead
    /// of following indices to three positions and three normals, loads that each wait for the
    /// last (docs/performance.md, session 46: −6 to −10 % render time on dining-room's 286k triangles).
    struct Corners {
        std::array<Vec3f, 3> p, n;  ///< n: the vertex normals, unset when flat()
        std::array<Vec2f, 3> uv;    ///< unset without uvs
        Vec3f ng;                   ///< unit face normal: hits and light samples reuse it
    };
    std::vector<float> m_cdf;
    std::vector<Corners> m_corners;
    float m_area = 0.f;
};

}  // namespace lpt
