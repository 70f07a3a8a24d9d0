// TriangleMesh: transforming to world space, the one validation pass every loader ends with, and
// the extension dispatch over the readers in core/loaders/.
#include "core/mesh.h"
#include "core/image_io.h"
#include "core/error.h"
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

namespace lpt {

void TriangleMesh::transform(const Transform& world_from_object) {
    for (Vec3f& p : positions) p = world_from_object.point(p);
    for (Vec3f& n : normals) {
        // A singular transform yields a zero or non-finite normal here; validate_mesh reports it.
        Vec3f t = world_from_object.normal(n);
        float len = t.norm();
        n = len > 0.f ? Vec3f(t / len) : t;
    }
    // Under a mirroring transform the edge cross product (geometric normal) picks up the sign of
    // det while shading normals (inverse transpose) do not, so the two would point to opposite
    // sides. Reversing each triangle's winding puts them back on the same side, as glTF
    // prescribes for negative-determinant nodes (pbrt tracks the same as swapsHandedness).
    if (world_from_object.m.topLeftCorner<3, 3>().determinant() < 0.f) {
        for (size_t t = 0; t + 2 < indices.size(); t += 3) std::swap(indices[t + 1], indices[t + 2]);
    }
}

namespace {

std::string vec_str(const Vec3f& v) {
    return "(" + std::to_string(v.x()) + ", " + std::to_string(v.y()) + ", " + std::to_string(v.z()) + ")";
}

}  // namespace

void validate_mesh(TriangleMesh& mesh, const std::string& file, const std::string& field, bool drop_degenerate) {
    auto fail = [&](const std::string& msg) { throw SceneError(file, field, msg); };
    const size_t nv = mesh.positions.size();
    if (!mesh.normals.empty() && mesh.normals.size() != nv)
        fail("mesh has " + std::to_string(mesh.normals.size()) + " normals but " + std::to_string(nv) + " positions");
    if (!mesh.uvs.empty() && mesh.uvs.size() != nv)
        fail("mesh has " + std::to_string(mesh.uvs.size()) + " uvs but " + std::to_string(nv) + " positions");
    if (mesh.indices.size() % 3 != 0)
        fail("index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3");

    for (size_t i = 0; i < nv; ++i)
        if (!mesh.positions[i].allFinite())
            fail("vertex " + std::to_string(i) + " has non-finite position " + vec_str(mesh.positions[i]));
    for (size_t i = 0; i < mesh.normals.size(); ++i) {
        Vec3f& n = mesh.normals[i];
        if (!n.allFinite()) fail("vertex " + std::to_string(i) + " has non-finite normal " + vec_str(n));
        // Renormalising here is what lets shading code take normals as unit without checking.
        float len = n.norm();
        if (!(len > 0.f)) fail("vertex " + std::to_string(i) + " has a zero-length normal");
        n /= len;
    }
    for (size_t i = 0; i < mesh.uvs.size(); ++i)
        if (!mesh.uvs[i].allFinite()) fail("vertex " + std::to_string(i) + " has a non-finite uv");

    for (size_t k = 0; k < mesh.indices.size(); ++k)
        if (mesh.indices[k] >= nv)
            fail("triangle " + std::to_string(k / 3) + " has vertex index " + std::to_string(mesh.indices[k]) +
                 " >= vertex count " + std::to_string(nv));

    // The area threshold is relative to the mesh's extent so it means the same at any scene scale.
    // Doubles, because float cross products of large coordinates cancel to zero or overflow.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = Eigen::Vector3d::Constant(-kInf);
    for (const Vec3f& p : mesh.positions) {
        lo = lo.cwiseMin(p.cast<double>());
        hi = hi.cwiseMax(p.cast<double>());
    }
    const double min_area = nv > 0 ? 1e-12 * (hi - lo).squaredNorm() : 0.0;
    size_t kept = 0;
    for (size_t t = 0; t < mesh.triangle_count(); ++t) {
        const uint32_t* tri = &mesh.indices[3 * t];
        Eigen::Vector3d a = mesh.positions[tri[0]].cast<double>();
        Eigen::Vector3d b = mesh.positions[tri[1]].cast<double>();
        Eigen::Vector3d c = mesh.positions[tri[2]].cast<double>();
        double area = 0.5 * (b - a).cross(c - a).norm();
        if (!(area >= min_area) || area == 0.0) {  // also catches a NaN area
            if (!drop_degenerate)
                fail("triangle " + std::to_string(t) + " (vertices " + std::to_string(tri[0]) + ", " +
                     std::to_string(tri[1]) + ", " + std::to_string(tri[2]) + ") has zero area");
            continue;
        }
        std::copy(tri, tri + 3, &mesh.indices[3 * kept]);
        ++kept;
    }
    mesh.indices.resize(3 * kept);
    if (kept == 0)
        fail(drop_degenerate && nv > 0 ? "mesh has no triangles left after dropping zero-area ones"
                                       : "mesh has no triangles");
}

void compute_vertex_normals(TriangleMesh& mesh) {
    const size_t nt = mesh.triangle_count();
    std::vector<Vec3f> sum(mesh.positions.size(), Vec3f::Zero());
    std::vector<Vec3f> face(nt);
    for (size_t t = 0; t < nt; ++t) {
        const uint32_t* idx = &mesh.indices[3 * t];
        const Vec3f p[3] = {mesh.positions[idx[0]], mesh.positions[idx[1]], mesh.positions[idx[2]]};
        face[t] = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
        for (int k = 0; k < 3; ++k) {
            const Vec3f a = (p[(k + 1) % 3] - p[k]).normalized(), b = (p[(k + 2) % 3] - p[k]).normalized();
            // atan2 of |a x b| and a.b: accurate for small and large angles alike.
            sum[idx[k]] += std::atan2(a.cross(b).norm(), a.dot(b)) * face[t];
        }
    }
    bool planar = true;
    for (size_t t = 0; t < nt && planar; ++t)
        for (int k = 0; k < 3; ++k)
            planar = planar && sum[mesh.indices[3 * t + k]].normalized().dot(face[t]) > 1.f - 1e-6f;
    if (planar) return;
    mesh.normals.resize(sum.size());
    for (size_t v = 0; v < sum.size(); ++v) {
        const float len = sum[v].norm();
        // A vertex no triangle uses keeps an arbitrary unit normal: nothing interpolates it.
        mesh.normals[v] = len > 0.f ? Vec3f(sum[v] / len) : Vec3f::UnitZ();
    }
}

TriangleMesh load_mesh_file(const std::string& path, bool flip_v, bool drop_degenerate) {
    const std::string ext = lower_extension(path);
    // flip_v is an OBJ convention (Mitsuba's flip_tex_coords); PLY and glTF uvs are taken as stored.
    if (ext == ".obj") return load_obj(path, flip_v, drop_degenerate);
    if (ext == ".ply") return load_ply(path);
    if (ext == ".gltf" || ext == ".glb") return load_gltf(path);
    throw SceneError(path, "", "unknown mesh file extension '" + ext + "' (expected .obj, .ply, .gltf or .glb)");
}

}  // namespace lpt
