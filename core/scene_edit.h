// Edit sequences (docs/edits.md): camera orbits or look-ats and shape translations, rotations
// and scalings, each value either constant or a list of keyframes interpolated linearly. Frame
// i of n is evaluated at t = i / n. Errors name the edits file and the field.
#pragma once
#include "core/scene.h"
#include <string>
#include <vector>

namespace lpt {

/// A value over t in [0, 1]: keyframes evenly spaced in t (one keyframe = constant).
struct Track {
    std::vector<Vec3f> keys;
    Vec3f at(float t) const;
};

struct ShapeEdit {
    std::string id;
    int shape = -1;
    Track translate, scale, rotate_angle;  ///< rotate_angle.x() holds degrees
    Vec3f rotate_axis = Vec3f::UnitY();
    Track pivot;  ///< rotation/scaling centre (default: the shape's bbox centre)
    bool has_pivot = false;
};

struct CameraEdit {
    enum class Kind { None, Orbit, LookAt } kind = Kind::None;
    Track azimuth, elevation;  ///< degrees (x component), for Orbit
    Vec3f pivot = Vec3f::Zero(), up = Vec3f::UnitY();
    Track origin, target, look_up;  ///< for LookAt
};

struct EditSequence {
    int frames = 1;
    CameraEdit camera;
    std::vector<ShapeEdit> shapes;
};

/// Parses `path` against `scene` (shape ids must exist). Throws SceneError(path, field, ...).
EditSequence load_edits(const std::string& path, const Scene& scene);

/// Whether the sequence at time t leaves the scene as loaded: every shape track at its identity
/// (no translation, unit scale, no rotation) and the orbit's angles 0; a look-at camera always
/// counts as an edit. Such a frame is the unedited view (an experiment's training view).
bool is_unedited(const EditSequence& edits, float t);

/// Applies the sequence at time t to `scene`, whose shapes' meshes are reset from `original`
/// first (so frames do not accumulate), then rebuilds the BVH and light sampler.
void apply_edits(const EditSequence& edits, float t, const std::vector<TriangleMesh>& original,
                 const Camera& original_camera, Scene& scene);

}  // namespace lpt
