#include "core/scene_edit.h"
#include "core/error.h"
#include "core/json_keys.h"
#include <nlohmann/json.hpp>
#include <fstream>

namespace lpt {

using nlohmann::json;

Vec3f Track::at(float t) const {
    if (keys.size() == 1) return keys[0];
    float x = std::clamp(t, 0.f, 1.f) * float(keys.size() - 1);
    size_t i = std::min(size_t(x), keys.size() - 2);
    float f = x - float(i);
    return (1.f - f) * keys[i] + f * keys[i + 1];
}

namespace {

struct Parser {
    std::string file;
    [[noreturn]] void fail(const std::string& field, const std::string& msg) const {
        throw SceneError(file, field, msg);
    }
    /// "azimut" would otherwise leave the camera where it is for every frame without a word.
    void only_keys(const json& obj, const std::string& field, const std::vector<const char*>& known) const {
        require_known_keys(obj, file, field, known);
    }
    float number(const json& j, const std::string& field) const { return require_finite_number(j, file, field); }

    Vec3f vec(const json& j, const std::string& field, bool scalar_ok) const {
        if (j.is_number()) {
            if (!scalar_ok) fail(field, "expected [x, y, z]");
            return Vec3f::Constant(number(j, field));
        }
        if (!j.is_array() || j.size() != 3)
            fail(field, scalar_ok ? "expected a number or [x, y, z]" : "expected [x, y, z]");
        Vec3f v;
        for (int i = 0; i < 3; ++i) v[i] = number(j[i], field);
        return v;
    }
    enum class Kind { Scalar, Vector, Scale };
    /// A constant or a list of keyframes (docs/edits.md): scalars are a number or a list of
    /// numbers; vectors [x,y,z] or a list of them; scales a number (uniform), [x,y,z], or a
    /// list of those, where a list of exactly three numbers reads as one [x,y,z].
    Track track(const json& j, const std::string& field, Kind kind) const {
        auto one = [&](const json& v, const std::string& f) {
            if (kind == Kind::Scalar) return Vec3f(number(v, f), 0.f, 0.f);
            return vec(v, f, kind == Kind::Scale);
        };
        bool keyframes = false;
        if (j.is_array() && !j.empty()) {
            if (kind == Kind::Scalar) keyframes = true;
            else if (kind == Kind::Vector) keyframes = j[0].is_array();
            else keyframes = j[0].is_array() || j.size() != 3;
        }
        Track t;
        if (!keyframes) {
            t.keys.push_back(one(j, field));
            return t;
        }
        for (size_t i = 0; i < j.size(); ++i) t.keys.push_back(one(j[i], field + "[" + std::to_string(i) + "]"));
        return t;
    }
};

Eigen::AlignedBox3f bounds(const TriangleMesh& m) {
    Eigen::AlignedBox3f b;
    for (const Vec3f& p : m.positions) b.extend(p);
    return b;
}

CameraEdit read_camera_edit(const Parser& p, const json& c, const Scene& scene) {
    CameraEdit cam;
    p.only_keys(c, "camera", {"orbit", "lookat"});
    if (c.contains("orbit") && c.contains("lookat")) p.fail("camera", "expected orbit or lookat, not both");
    if (c.contains("orbit")) {
        const json& o = c["orbit"];
        p.only_keys(o, "camera.orbit", {"azimuth", "elevation", "pivot", "up"});
        cam.kind = CameraEdit::Kind::Orbit;
        cam.azimuth = o.contains("azimuth") ? p.track(o["azimuth"], "camera.orbit.azimuth", Parser::Kind::Scalar)
                                            : Track{{Vec3f::Zero()}};
        cam.elevation = o.contains("elevation")
                            ? p.track(o["elevation"], "camera.orbit.elevation", Parser::Kind::Scalar)
                            : Track{{Vec3f::Zero()}};
        cam.pivot = o.contains("pivot") ? p.vec(o["pivot"], "camera.orbit.pivot", false) : scene.bounds_center();
        if (o.contains("up")) {
            cam.up = p.vec(o["up"], "camera.orbit.up", false);
            if (cam.up.norm() == 0.f) p.fail("camera.orbit.up", "zero vector");
            cam.up.normalize();
        }
    } else if (c.contains("lookat")) {
        const json& l = c["lookat"];
        p.only_keys(l, "camera.lookat", {"origin", "target", "up"});
        cam.kind = CameraEdit::Kind::LookAt;
        for (const char* k : {"origin", "target", "up"})
            if (!l.contains(k)) p.fail(std::string("camera.lookat.") + k, "missing");
        cam.origin = p.track(l["origin"], "camera.lookat.origin", Parser::Kind::Vector);
        cam.target = p.track(l["target"], "camera.lookat.target", Parser::Kind::Vector);
        cam.look_up = p.track(l["up"], "camera.lookat.up", Parser::Kind::Vector);
    } else {
        p.fail("camera", "expected {\"orbit\": ...} or {\"lookat\": ...}");
    }
    return cam;
}

std::vector<ShapeEdit> read_shape_edits(const Parser& p, const json& list, const Scene& scene) {
    if (!list.is_array()) p.fail("shapes", "expected an array");
    std::vector<ShapeEdit> out;
    for (size_t i = 0; i < list.size(); ++i) {
        const json& s = list[i];
        const std::string f = "shapes[" + std::to_string(i) + "]";
        p.only_keys(s, f, {"id", "translate", "rotate", "scale", "pivot"});
        if (!s.contains("id") || !s["id"].is_string()) p.fail(f + ".id", "missing shape id");
        ShapeEdit e;
        e.id = s["id"].get<std::string>();
        e.shape = scene.find_shape(e.id);
        if (e.shape < 0) p.fail(f + ".id", "no shape '" + e.id + "' in the scene");
        e.translate = s.contains("translate") ? p.track(s["translate"], f + ".translate", Parser::Kind::Vector)
                                              : Track{{Vec3f::Zero()}};
        e.scale = s.contains("scale") ? p.track(s["scale"], f + ".scale", Parser::Kind::Scale) : Track{{Vec3f::Ones()}};
        e.rotate_angle = Track{{Vec3f::Zero()}};
        if (s.contains("rotate")) {
            const json& r = s["rotate"];
            p.only_keys(r, f + ".rotate", {"axis", "angle"});
            if (!r.contains("angle"))
                p.fail(f + ".rotate", "expected {\"axis\": [x,y,z], \"angle\": degrees or keyframes}");
            if (r.contains("axis")) e.rotate_axis = p.vec(r["axis"], f + ".rotate.axis", false);
            if (e.rotate_axis.norm() == 0.f) p.fail(f + ".rotate.axis", "zero axis");
            e.rotate_axis.normalize();
            e.rotate_angle = p.track(r["angle"], f + ".rotate.angle", Parser::Kind::Scalar);
        }
        if (s.contains("pivot")) {
            e.pivot = p.track(s["pivot"], f + ".pivot", Parser::Kind::Vector);
            e.has_pivot = true;
        }
        out.push_back(e);
    }
    return out;
}

}  // namespace

EditSequence load_edits(const std::string& path, const Scene& scene) {
    Parser p{path};
    std::ifstream in(path);
    if (!in) throw SceneError(path, "", "cannot open file");
    json j;
    try {
        j = json::parse(in);
    } catch (const json::exception& e) {
        throw SceneError(path, "", std::string("malformed JSON: ") + e.what());
    }
    if (!j.is_object()) p.fail("", "top level must be an object");
    EditSequence seq;
    p.only_keys(j, "", {"frames", "camera", "shapes"});
    if (j.contains("frames")) {
        // read as int64 first: get<int>() of 4294967297 wrapped to 1
        const json& f = j["frames"];
        if (!f.is_number_integer() || f.get<int64_t>() < 1 || f.get<int64_t>() > 1000000)
            p.fail("frames", "expected an integer in [1, 1000000]");
        seq.frames = int(f.get<int64_t>());
    }
    if (j.contains("camera")) seq.camera = read_camera_edit(p, j["camera"], scene);
    if (j.contains("shapes")) seq.shapes = read_shape_edits(p, j["shapes"], scene);
    return seq;
}

namespace {

bool moves(const ShapeEdit& e, float t) {
    return e.translate.at(t) != Vec3f::Zero() || e.scale.at(t) != Vec3f::Ones() || e.rotate_angle.at(t).x() != 0.f;
}

bool orbits(const CameraEdit& c, float t) {
    return c.kind == CameraEdit::Kind::Orbit && (c.azimuth.at(t).x() != 0.f || c.elevation.at(t).x() != 0.f);
}

}  // namespace

bool is_unedited(const EditSequence& edits, float t) {
    for (const ShapeEdit& e : edits.shapes)
        if (moves(e, t)) return false;
    return edits.camera.kind != CameraEdit::Kind::LookAt && !orbits(edits.camera, t);
}

void apply_edits(const EditSequence& edits, float t, const std::vector<TriangleMesh>& original,
                 const Camera& original_camera, Scene& scene) {
    for (size_t i = 0; i < scene.shapes.size(); ++i) scene.shapes[i].mesh = original[i];
    for (const ShapeEdit& e : edits.shapes) {
        // An edit at rest leaves the mesh as loaded: p + (v − p) is not always v in floats, and an
        // unedited frame must be the training view bit for bit (its reference is the training one).
        if (!moves(e, t)) continue;
        TriangleMesh& m = scene.shapes[e.shape].mesh;
        Vec3f pivot = e.has_pivot ? e.pivot.at(t) : bounds(original[e.shape]).center();
        Transform xf = Transform::translate(e.translate.at(t)) * Transform::translate(pivot) *
                       Transform::rotate(e.rotate_axis, e.rotate_angle.at(t).x()) * Transform::scale(e.scale.at(t)) *
                       Transform::translate(-pivot);
        m.transform(xf);
    }
    scene.camera = original_camera;
    const CameraEdit& c = edits.camera;
    if (orbits(c, t)) {
        const Transform& w = original_camera.world_from_camera;
        Vec3f right = w.vector(Vec3f::UnitX()).normalized();  // camera +x (image left): elevation axis
        Transform r = Transform::rotate(c.up, c.azimuth.at(t).x()) * Transform::rotate(right, c.elevation.at(t).x());
        scene.camera.world_from_camera = Transform::translate(c.pivot) * r * Transform::translate(-c.pivot) * w;
    } else if (c.kind == CameraEdit::Kind::LookAt) {
        scene.camera.world_from_camera = Transform::look_at(c.origin.at(t), c.target.at(t), c.look_up.at(t));
    }
    scene.build();
}

}  // namespace lpt
