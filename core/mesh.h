// Triangle meshes and their readers. A loaded mesh is validated once (finite positions,
// indices in range, no zero-area triangles) so nothing downstream needs to re-check.
#pragma once
#include "core/geometry.h"
#include "core/transform.h"
#include <cstdint>
#include <string>
#include <vector>

namespace lpt {

struct TriangleMesh {
    std::vector<Vec3f> positions;
    std::vector<Vec3f> normals;     ///< per vertex, empty if none (then face normals are used)
    std::vector<Vec2f> uvs;         ///< per vertex, empty if none
    std::vector<uint32_t> indices;  ///< 3 per triangle
    size_t triangle_count() const { return indices.size() / 3; }
    void transform(const Transform& world_from_object);
};

/// Throws SceneError(file, field, ...) if positions/normals/uvs are not finite, an index is out of
/// range, or a triangle has zero area (area < 1e-12 relative to the mesh's bounding box).
/// `drop_degenerate`: instead of failing on zero-area triangles, remove them (Mitsuba does);
/// NaN and range errors always fail.
void validate_mesh(TriangleMesh& mesh, const std::string& file, const std::string& field, bool drop_degenerate = false);

/// Smooth vertex normals for a mesh that has none, as Mitsuba 3 computes them when an obj/ply
/// file stores no normals and face_normals is off: each triangle adds its unit normal times its
/// interior angle at the vertex (Thürmer & Wüthrich 1998). Call after the world transform (the
/// angles are world-space angles, as Mitsuba's). Where every vertex normal would equal the normals
/// of all triangles around it (a piecewise planar mesh: walls, quads), the normals stay empty:
/// flat shading is then the same surface and keeps the flat fast paths. Zero-area triangles
/// must be gone (validate_mesh).
void compute_vertex_normals(TriangleMesh& mesh);

/// Readers. Each throws SceneError naming `path` on missing file / parse error; they validate.
/// OBJ: v, vt, vn, faces with v, v/vt, v//vn, v/vt/vn; polygons fan-triangulated. Mitsuba
/// flips the v texture coordinate on load (`flip_tex_coords`): pass flip_v=true for its scenes.
/// drop_degenerate: remove zero-area triangles instead of failing (validate_mesh), as Mitsuba
/// does; the Mitsuba XML loader passes true, our JSON format keeps rejecting them.
TriangleMesh load_obj(const std::string& path, bool flip_v = false, bool drop_degenerate = false);
/// PLY, ascii and binary (little/big endian): vertex x y z [nx ny nz] [u v | s t | texture_u ...],
/// face vertex_indices / vertex_index lists (polygons fan-triangulated).
TriangleMesh load_ply(const std::string& path);
/// glTF 2.0 (.gltf / .glb): all triangle primitives of all meshes, node transforms applied.
TriangleMesh load_gltf(const std::string& path);
/// Dispatch on extension (.obj, .ply, .gltf, .glb). flip_v and drop_degenerate reach the OBJ
/// reader only: PLY and glTF uvs are taken as stored and those readers always validate strictly.
TriangleMesh load_mesh_file(const std::string& path, bool flip_v = false, bool drop_degenerate = false);

/// Analytic shapes, tessellated in object space (Mitsuba's canonical forms).
TriangleMesh make_rectangle();                                 ///< [-1,1]^2 at z=0, normal +z, uv in [0,1]^2
TriangleMesh make_cube();                                      ///< [-1,1]^3, outward normals, flat faces
TriangleMesh make_sphere(int rings = 64, int segments = 128);  ///< unit sphere, smooth normals

}  // namespace lpt
