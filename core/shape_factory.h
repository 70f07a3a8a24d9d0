// Shapes built from their descriptions (Props), as BSDFs are by make_bsdf: the JSON and Mitsuba
// XML loaders only translate syntax into Props (filenames made absolute, transforms parsed) and
// call these, so loading, placing, flipping and validating a mesh is written once.
#pragma once
#include "core/props.h"
#include "core/shape.h"

namespace lpt {

/// What a scene format assumes where the file says nothing. Mitsuba 3 flips OBJ texture v,
/// drops zero-area triangles and smooth-shades a mesh file without normals; latentpt JSON keeps
/// mesh files as stored and rejects degenerate triangles.
struct ShapeDefaults {
    bool flip_tex_coords = false;
    bool drop_degenerate = false;
    bool smooth_missing_normals = false;
};
inline constexpr ShapeDefaults kMitsubaShapeDefaults{true, true, true};
inline constexpr ShapeDefaults kJsonShapeDefaults{false, false, false};

/// A shape (id and material left to the loader) from `props`:
///   type "obj" | "ply" | "gltf": filename (absolute; the extension picks the reader),
///       flip_tex_coords (OBJ), face_normals;
///   type "rectangle" | "cube" | "sphere" (center, radius: Mitsuba's to_world · T(center) · S(r));
///   every type: to_world (a Transform), flip_normals.
/// Errors are SceneErrors naming props.file and props.where + the key.
Shape make_shape(const Props& props, const ShapeDefaults& defaults);

/// The same placing, flipping and validation for an object-space mesh the loader built itself
/// (latentpt JSON's inline "mesh"); props holds to_world and flip_normals.
Shape make_shape_from_mesh(TriangleMesh object_mesh, const Props& props, const ShapeDefaults& defaults);

}  // namespace lpt
