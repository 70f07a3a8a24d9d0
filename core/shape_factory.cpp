#include "core/shape_factory.h"
#include "core/mesh.h"

namespace lpt {

namespace {

/// Turns a surface inside out: reversed winding and negated normals (Mitsuba `flip_normals`).
void flip_normals(TriangleMesh& m) {
    for (size_t t = 0; t < m.triangle_count(); ++t) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
    for (auto& n : m.normals) n = -n;
}

bool is_mesh_file(const std::string& type) { return type == "obj" || type == "ply" || type == "gltf"; }

TriangleMesh load_mesh(const Props& p, const ShapeDefaults& defaults) {
    const std::string filename = p.get_string("filename");
    try {
        return load_mesh_file(filename, p.get_bool("flip_tex_coords", defaults.flip_tex_coords),
                              defaults.drop_degenerate);
    } catch (const SceneError& e) {
        p.fail("filename", e.what());
    }
}

/// Object to world: Mitsuba's sphere is to_world · translate(center) · scale(radius).
Transform world_from_object(const Props& p) {
    Transform to_world = p.get_transform("to_world", Transform());
    if (p.type != "sphere") return to_world;
    const float r = p.get_float("radius", 1.f);
    if (!(r > 0.f)) p.fail("radius", "must be > 0");
    const Vec3f center = p.get_rgb("center", Eigen::Array3f::Zero()).matrix();
    return to_world * Transform::translate(center) * Transform::scale(Vec3f::Constant(r));
}

}  // namespace

Shape make_shape_from_mesh(TriangleMesh object_mesh, const Props& p, const ShapeDefaults& defaults) {
    Shape shape;
    shape.mesh = std::move(object_mesh);
    shape.face_normals = p.get_bool("face_normals", false);
    shape.mesh.transform(world_from_object(p));
    if (p.get_bool("flip_normals", false)) flip_normals(shape.mesh);
    validate_mesh(shape.mesh, p.file, p.where, defaults.drop_degenerate);
    const bool from_file = is_mesh_file(p.type);
    if (from_file && defaults.smooth_missing_normals && !shape.face_normals && shape.mesh.normals.empty())
        compute_vertex_normals(shape.mesh);
    return shape;
}

Shape make_shape(const Props& p, const ShapeDefaults& defaults) {
    TriangleMesh mesh;
    if (is_mesh_file(p.type)) mesh = load_mesh(p, defaults);
    else if (p.type == "rectangle") mesh = make_rectangle();
    else if (p.type == "cube") mesh = make_cube();
    else if (p.type == "sphere") mesh = make_sphere();
    else p.fail("type", "unknown shape type '" + p.type + "' (known: obj, ply, gltf, rectangle, cube, sphere)");
    return make_shape_from_mesh(std::move(mesh), p, defaults);
}

}  // namespace lpt
