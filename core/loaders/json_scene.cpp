// latentpt's JSON scene format (docs/scene-format.md). Errors name the JSON path of the bad
// field, e.g. `scene.json: field 'shapes[2].material': unknown material 'whte'`.
#include "core/bsdf.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_keys.h"
#include "core/scene_loader.h"
#include "core/shape_factory.h"
#include "core/envmap.h"
#include "core/texture.h"
#include <nlohmann/json.hpp>
#include <climits>
#include <filesystem>
#include <fstream>
#include <vector>

namespace lpt {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

struct Ctx {
    std::string file;
    fs::path dir;
    [[noreturn]] void fail(const std::string& field, const std::string& msg) const {
        throw SceneError(file, field, msg);
    }

    float number(const json& j, const std::string& field) const { return require_finite_number(j, file, field); }
    Vec3f vec3(const json& j, const std::string& field) const {
        if (j.is_number()) return Vec3f::Constant(number(j, field));
        if (!j.is_array() || j.size() != 3) fail(field, "expected an array of 3 numbers");
        return Vec3f(number(j[0], field + "[0]"), number(j[1], field + "[1]"), number(j[2], field + "[2]"));
    }
    int integer(const json& j, const std::string& field) const {
        if (!j.is_number_integer()) fail(field, "expected an integer");
        // Beyond int's range get<int>() would wrap (2^32 + 1 spp -> 1 spp) without a word.
        if (j.is_number_unsigned() ? j.get<unsigned long long>() > INT_MAX
                                   : (j.get<long long>() < INT_MIN || j.get<long long>() > INT_MAX))
            fail(field, "integer out of range");
        return j.get<int>();
    }
    std::string string(const json& j, const std::string& field) const {
        if (!j.is_string()) fail(field, "expected a string");
        return j.get<std::string>();
    }
    const json* opt(const json& obj, const char* key) const {
        auto it = obj.find(key);
        return it == obj.end() ? nullptr : &*it;
    }
    /// A -D path with a typo makes an unknown key too, so it fails here as well.
    void only_keys(const json& obj, const std::string& field, const std::vector<const char*>& known) const {
        require_known_keys(obj, file, field, known);
    }

    Transform transform_op(const json& op, const std::string& field) const {
        if (!op.is_object() || op.size() != 1)
            fail(field, "expected one of {\"translate\"|\"scale\"|\"rotate\"|\"lookat\"|\"matrix\": ...}");
        auto first = op.begin();
        const std::string key = first.key();
        const json& v = first.value();
        std::string f = field + "." + key;
        if (key == "translate") return Transform::translate(vec3(v, f));
        if (key == "scale") return Transform::scale(vec3(v, f));
        if (key == "rotate") {
            if (!v.is_object() || !v.contains("axis") || !v.contains("angle"))
                fail(f, "expected {\"axis\": [x,y,z], \"angle\": degrees}");
            only_keys(v, f, {"axis", "angle"});
            Vec3f axis = vec3(v["axis"], f + ".axis");
            if (axis.norm() == 0.f) fail(f + ".axis", "axis has zero length");
            return Transform::rotate(axis, number(v["angle"], f + ".angle"));
        }
        if (key == "lookat") {
            if (!v.is_object()) fail(f, "expected {\"origin\", \"target\", \"up\"}");
            for (const char* k : {"origin", "target", "up"})
                if (!v.contains(k)) fail(f + "." + k, "missing");
            only_keys(v, f, {"origin", "target", "up"});
            try {
                return Transform::look_at(vec3(v["origin"], f + ".origin"), vec3(v["target"], f + ".target"),
                                          vec3(v["up"], f + ".up"));
            } catch (const std::invalid_argument& e) {
                fail(f, e.what());
            }
        }
        if (key == "matrix") {
            if (!v.is_array() || v.size() != 16) fail(f, "expected 16 numbers, row-major");
            Eigen::Matrix4f m;
            for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = number(v[i], f + "[" + std::to_string(i) + "]");
            if (std::abs(m.topLeftCorner<3, 3>().determinant()) < 1e-12f) fail(f, "matrix is singular");
            return Transform(m);
        }
        fail(field, "unknown transform operation '" + key + "'");
    }
    /// One op object, or a list of ops applied in order (each later op left-multiplies).
    Transform transform(const json& j, const std::string& field) const {
        if (!j.is_object() && !j.is_array()) fail(field, "expected a transform object or a list of them");
        Transform t;
        if (j.is_object()) t = transform_op(j, field);
        else
            for (size_t i = 0; i < j.size(); ++i) t = transform_op(j[i], field + "[" + std::to_string(i) + "]") * t;
        // as the XML loader: a camera whose frame collapses sends Embree rays of zero direction
        // (an assertion abort), a shape whose frame collapses has no surface
        const float det = t.m.topLeftCorner<3, 3>().determinant();
        if (!(std::abs(det) > 0.f) || !t.inv.allFinite()) fail(field, "transform is singular");
        return t;
    }

    /// Plugin description: numbers → float, 3-arrays → rgb, objects → nested Props. A nested
    /// {"type": "bitmap", "filename": ...} gets its filename resolved against the scene's folder
    /// here, so the Props stand on their own (core/texture.h reads them).
    Props props(const json& j, const std::string& field) const {
        if (!j.is_object()) fail(field, "expected an object");
        Props p;
        p.file = file;
        p.where = field;
        if (!j.contains("type")) fail(field + ".type", "missing");
        p.type = string(j["type"], field + ".type");
        for (const auto& [k, v] : j.items()) {
            if (k == "type" || is_comment_key(k)) continue;
            std::string f = field + "." + k;
            if (v.is_boolean()) p.values[k] = v.get<bool>();
            else if (v.is_number()) p.values[k] = number(v, f);
            else if (v.is_string()) p.values[k] = v.get<std::string>();
            else if (v.is_array()) p.values[k] = Eigen::Array3f(vec3(v, f).array());
            else if (v.is_object()) p.values[k] = std::make_shared<Props>(props(v, f));
            else fail(f, "unsupported value");
        }
        if (p.type == "bitmap")
            if (auto it = p.values.find("filename"); it != p.values.end())
                if (auto* name = std::get_if<std::string>(&it->second); name && !name->empty())
                    *name = fs::absolute(dir / *name).lexically_normal().string();
        return p;
    }
};

/// The element of array `node` that path part `part` ("0", "12") names; SceneError otherwise.
json& array_element(json& node, const std::string& part, const std::string& key, const std::string& file) {
    const bool digits = !part.empty() && part.size() <= 9 && part.find_first_not_of("0123456789") == std::string::npos;
    if (!digits || std::stoul(part) >= node.size())
        throw SceneError(
            file, key, "cannot override: '" + part + "' is not an index of an array of " + std::to_string(node.size()));
    return node[std::stoul(part)];
}

void apply_define(json& root, const std::string& key, const std::string& value, const std::string& file) {
    // "integrator.spp=64", "shapes.2.material=red": walk the path (array elements by index),
    // parse the value as JSON (fallback: string).
    json* node = &root;
    size_t start = 0;
    while (true) {
        const size_t dot = key.find('.', start);
        const std::string part = key.substr(start, dot - start);
        if (!node->is_object() && !node->is_array() && !node->is_null())
            throw SceneError(file, key, "cannot override: not an object path");
        json& child = node->is_array() ? array_element(*node, part, key, file) : (*node)[part];
        if (dot == std::string::npos) {
            json v = json::parse(value, nullptr, false);
            child = v.is_discarded() ? json(value) : v;
            return;
        }
        node = &child;
        start = dot + 1;
    }
}

bool known_shape_type(const std::string& t) {
    return t == "obj" || t == "ply" || t == "gltf" || t == "mesh" || t == "rectangle" || t == "cube" || t == "sphere";
}

bool is_mesh_file(const std::string& t) { return t == "obj" || t == "ply" || t == "gltf"; }

/// A shape's keys: the ones every shape takes and its type's (docs/scene-format.md "shapes").
void check_shape_keys(const Ctx& c, const json& s, const std::string& f, const std::string& type) {
    std::vector<const char*> keys = {"id", "type", "material", "emitter", "to_world", "face_normals", "flip_normals"};
    if (type == "obj") keys.insert(keys.end(), {"filename", "flip_tex_coords"});
    else if (is_mesh_file(type)) keys.push_back("filename");
    else if (type == "mesh") keys.insert(keys.end(), {"positions", "indices"});
    else if (type == "sphere") keys.insert(keys.end(), {"center", "radius"});
    c.only_keys(s, f, keys);
}

/// A shape object's placement and file keys as the Props make_shape reads (the rest of the object,
/// material and emitter, is read by the caller); the filename relative to the scene's folder.
Props shape_props(const Ctx& c, const json& s, const std::string& f, const std::string& type) {
    Props p;
    p.type = type;
    p.file = c.file;
    p.where = f;
    for (const char* key : {"face_normals", "flip_normals"})
        if (auto* v = c.opt(s, key)) {
            if (!v->is_boolean()) c.fail(f + "." + key, "expected a boolean");
            p.values[key] = v->get<bool>();
        }
    if (auto* v = c.opt(s, "flip_tex_coords")) {
        if (!v->is_boolean()) c.fail(f + ".flip_tex_coords", "expected a boolean");
        p.values["flip_tex_coords"] = v->get<bool>();
    }
    if (is_mesh_file(type)) {
        if (!s.contains("filename")) c.fail(f + ".filename", "missing");
        p.values["filename"] = (c.dir / c.string(s["filename"], f + ".filename")).string();
    }
    if (type == "sphere") {
        if (auto* v = c.opt(s, "radius")) p.values["radius"] = c.number(*v, f + ".radius");
        if (auto* v = c.opt(s, "center")) p.values["center"] = Eigen::Array3f(c.vec3(*v, f + ".center").array());
    }
    if (auto* t = c.opt(s, "to_world")) p.values["to_world"] = c.transform(*t, f + ".to_world");
    return p;
}

/// latentpt JSON's inline "mesh": positions and polygons (fan-triangulated), in object space.
TriangleMesh inline_mesh(const Ctx& c, const json& s, const std::string& f) {
    TriangleMesh mesh;
    const json* pj = c.opt(s, "positions");
    const json* xj = c.opt(s, "indices");
    if (!pj || !pj->is_array()) c.fail(f + ".positions", "expected an array of [x,y,z]");
    if (!xj || !xj->is_array()) c.fail(f + ".indices", "expected an array of [i,j,k] (or polygons, fan-triangulated)");
    for (size_t k = 0; k < pj->size(); ++k)
        mesh.positions.push_back(c.vec3((*pj)[k], f + ".positions[" + std::to_string(k) + "]"));
    for (size_t k = 0; k < xj->size(); ++k) {
        std::string ff = f + ".indices[" + std::to_string(k) + "]";
        const json& poly = (*xj)[k];
        if (!poly.is_array() || poly.size() < 3) c.fail(ff, "expected a polygon of >= 3 vertex indices");
        std::vector<uint32_t> vs;
        for (const auto& x : poly) {
            int id = c.integer(x, ff);
            if (id < 0 || id >= int(mesh.positions.size()))
                c.fail(ff, "vertex index " + std::to_string(id) + " out of range [0, " +
                               std::to_string(mesh.positions.size()) + ")");
            vs.push_back(uint32_t(id));
        }
        for (size_t t = 1; t + 1 < vs.size(); ++t) mesh.indices.insert(mesh.indices.end(), {vs[0], vs[t], vs[t + 1]});
    }
    return mesh;
}

}  // namespace

namespace {

void read_integrator(const Ctx& c, const json& root, IntegratorSettings& s) {
    const json* ij = c.opt(root, "integrator");
    if (!ij) return;
    c.only_keys(*ij, "integrator", {"max_depth", "rr_depth", "spp", "sampler", "light_sampling"});
    if (auto* v = c.opt(*ij, "max_depth")) s.max_depth = c.integer(*v, "integrator.max_depth");
    if (auto* v = c.opt(*ij, "rr_depth")) s.rr_depth = c.integer(*v, "integrator.rr_depth");
    // the XML loader's ranges
    if (s.max_depth < -1) c.fail("integrator.max_depth", "must be >= -1 (-1: unbounded)");
    if (s.rr_depth < 1) c.fail("integrator.rr_depth", "must be >= 1");
    if (auto* v = c.opt(*ij, "spp")) s.spp = c.integer(*v, "integrator.spp");
    if (s.spp < 1) c.fail("integrator.spp", "must be >= 1");
    if (auto* v = c.opt(*ij, "sampler")) {
        std::string m = c.string(*v, "integrator.sampler");
        if (!parse_sampler(m, s.sampler))
            c.fail("integrator.sampler", "expected sobol or independent, got '" + m + "'");
    }
    if (auto* v = c.opt(*ij, "light_sampling")) {
        std::string m = c.string(*v, "integrator.light_sampling");
        if (m == "power") s.light_sampling = LightSampling::Power;
        else if (m == "area") s.light_sampling = LightSampling::Area;
        else if (m == "uniform") s.light_sampling = LightSampling::Uniform;
        else c.fail("integrator.light_sampling", "expected power, area or uniform, got '" + m + "'");
    }
}

void read_camera(const Ctx& c, const json& root, Camera& cam) {
    const json* cj = c.opt(root, "camera");
    if (!cj) c.fail("camera", "missing");
    c.only_keys(*cj, "camera",
                {"type", "fov", "fov_axis", "to_world", "width", "height", "near_clip", "far_clip", "filter"});
    if (auto* t = c.opt(*cj, "type"); t && c.string(*t, "camera.type") != "perspective")
        c.fail("camera.type", "unknown camera type '" + t->get<std::string>() + "' (known: perspective)");
    if (auto* v = c.opt(*cj, "fov")) cam.fov = c.number(*v, "camera.fov");
    if (!(cam.fov > 0.f && cam.fov < 180.f)) c.fail("camera.fov", "must be in (0, 180) degrees");
    if (auto* v = c.opt(*cj, "fov_axis")) {
        std::string a = c.string(*v, "camera.fov_axis");
        if (a == "x") cam.fov_axis = FovAxis::X;
        else if (a == "y") cam.fov_axis = FovAxis::Y;
        else if (a == "smaller") cam.fov_axis = FovAxis::Smaller;
        else if (a == "larger") cam.fov_axis = FovAxis::Larger;
        else c.fail("camera.fov_axis", "expected x, y, smaller or larger");
    }
    if (auto* v = c.opt(*cj, "to_world")) cam.world_from_camera = c.transform(*v, "camera.to_world");
    if (auto* v = c.opt(*cj, "width")) cam.width = c.integer(*v, "camera.width");
    if (auto* v = c.opt(*cj, "height")) cam.height = c.integer(*v, "camera.height");
    if (cam.width < 1 || cam.height < 1) c.fail("camera.width", "resolution must be positive");
    if (auto* v = c.opt(*cj, "near_clip")) cam.near_clip = c.number(*v, "camera.near_clip");
    if (auto* v = c.opt(*cj, "far_clip")) cam.far_clip = c.number(*v, "camera.far_clip");
    // the XML loader's ranges: outside them every ray is clipped and the image is black
    if (!(cam.near_clip > 0.f)) c.fail("camera.near_clip", "must be > 0");
    if (!(cam.far_clip > cam.near_clip)) c.fail("camera.far_clip", "must be > near_clip");
    if (auto* f = c.opt(*cj, "filter")) {
        std::string ft = f->is_object() && f->contains("type") ? c.string((*f)["type"], "camera.filter.type") : "";
        if (ft == "box") cam.filter = {PixelFilter::Type::Box, 0.5f};
        else if (ft == "tent") cam.filter = {PixelFilter::Type::Tent, 1.f};
        else c.fail("camera.filter.type", "expected box or tent");
        c.only_keys(*f, "camera.filter", {"type", "radius"});
        if (auto* r = c.opt(*f, "radius")) cam.filter.radius = c.number(*r, "camera.filter.radius");
        if (!(cam.filter.radius > 0.f)) c.fail("camera.filter.radius", "must be > 0");
    }
}

std::map<std::string, int> read_materials(const Ctx& c, const json& root, Scene& scene) {
    std::map<std::string, int> material_ids;
    if (const json* mj = c.opt(root, "materials")) {
        if (!mj->is_object()) c.fail("materials", "expected an object of named materials");
        for (const auto& [name, m] : mj->items()) {
            material_ids[name] = int(scene.materials.size());
            scene.materials.push_back(c.props(m, "materials." + name));
        }
    }

    return material_ids;
}

void read_shapes(const Ctx& c, const json& root, const std::map<std::string, int>& material_ids, Scene& scene) {
    const json* sj = c.opt(root, "shapes");
    if (!sj || !sj->is_array()) c.fail("shapes", "missing or not an array");
    for (size_t i = 0; i < sj->size(); ++i) {
        const json& s = (*sj)[i];
        std::string f = "shapes[" + std::to_string(i) + "]";
        if (!s.is_object()) c.fail(f, "expected an object");
        const std::string id = s.contains("id") ? c.string(s["id"], f + ".id") : "shape" + std::to_string(i);
        if (scene.find_shape(id) >= 0) c.fail(f + ".id", "duplicate shape id '" + id + "'");
        if (!s.contains("type")) c.fail(f + ".type", "missing");
        const std::string type = c.string(s["type"], f + ".type");
        if (!known_shape_type(type))
            c.fail(f + ".type",
                   "unknown shape type '" + type + "' (known: obj, ply, gltf, mesh, rectangle, cube, sphere)");
        check_shape_keys(c, s, f, type);
        const Props props = shape_props(c, s, f, type);
        Shape shape = type == "mesh" ? make_shape_from_mesh(inline_mesh(c, s, f), props, kJsonShapeDefaults)
                                     : make_shape(props, kJsonShapeDefaults);
        shape.id = id;

        const json* mat = c.opt(s, "material");
        if (!mat) c.fail(f + ".material", "missing");
        if (mat->is_string()) {
            auto it = material_ids.find(mat->get<std::string>());
            if (it == material_ids.end()) c.fail(f + ".material", "unknown material '" + mat->get<std::string>() + "'");
            shape.material = it->second;
        } else {
            shape.material = int(scene.materials.size());
            scene.materials.push_back(c.props(*mat, f + ".material"));
        }
        if (const json* ej = c.opt(s, "emitter")) {
            Props ep = c.props(*ej, f + ".emitter");
            if (ep.type != "area")
                c.fail(f + ".emitter.type", "shapes take emitters of type 'area', got '" + ep.type + "'");
            shape.emitter = int(scene.emitters.size());
            PropsReadLog read;
            scene.emitters.push_back(make_area_emitter(ep, int(scene.shapes.size())));
            read.require_all_read(ep);
        }
        scene.shapes.push_back(std::move(shape));
    }
}

void read_environment(const Ctx& c, const json& root, Scene& scene) {
    if (const json* ej = c.opt(root, "emitters")) {
        if (!ej->is_array()) c.fail("emitters", "expected an array");
        for (size_t i = 0; i < ej->size(); ++i) {
            std::string f = "emitters[" + std::to_string(i) + "]";
            const json& ejson = (*ej)[i];
            json plain = ejson;  // to_world is a transform, not a plugin value
            if (plain.is_object()) plain.erase("to_world");
            Props ep = c.props(plain, f);
            if (ep.type != "constant" && ep.type != "envmap")
                c.fail(f + ".type",
                       "top-level emitters must be 'constant' or 'envmap' (area lights belong inside a shape), got '" +
                           ep.type + "'");
            if (scene.environment >= 0) c.fail(f, "only one environment emitter is supported");
            if (ep.type == "envmap") {
                // {"type": "envmap", "filename": "sky.exr", "scale": 1, "to_world": ...}
                c.only_keys(ejson, f, {"type", "filename", "scale", "to_world"});
                const std::string name = ep.get_string("filename", "");
                if (name.empty()) c.fail(f + ".filename", "missing");
                ep.values["filename"] = fs::absolute(c.dir / name).lexically_normal().string();
                if (auto* t = c.opt(ejson, "to_world")) ep.values["to_world"] = c.transform(*t, f + ".to_world");
            }
            PropsReadLog read;
            const Emitter e = make_environment_emitter(ep);
            read.require_all_read(ep);
            scene.environment = int(scene.emitters.size());
            scene.emitters.push_back(e);
        }
    }
}

/// Validates every material once, now, so errors point at the file before rendering starts
/// (check_bsdf_description: values, unread keys, textures where a plain colour is read).
void validate_materials(const Scene& scene) {
    for (size_t mi = 0; mi < scene.materials.size(); ++mi) {
        const Props& m = scene.materials[mi];
        try {
            check_bsdf_description(m);
        } catch (const SceneError& e) {
            // Name the shapes too: a material (and its texture) may serve several.
            std::string users;
            for (const Shape& s : scene.shapes)
                if (s.material == int(mi)) users += (users.empty() ? "" : ", ") + std::string("'") + s.id + "'";
            throw e.with_note(users.empty() ? std::string() : " (material of shape " + users + ")");
        }
    }
}

}  // namespace

Scene load_scene_json(const std::string& path, const std::map<std::string, std::string>& defines) {
    Ctx c{path, fs::path(path).parent_path()};
    std::ifstream in(path);
    if (!in) throw SceneError(path, "", "cannot open file");
    json root;
    try {
        root = json::parse(in);
    } catch (const json::exception& e) {  // parse_error, and out_of_range for overflowing numbers
        throw SceneError(path, "", std::string("malformed JSON: ") + e.what());
    }
    if (!root.is_object()) c.fail("", "top level must be an object");
    for (const auto& [k, v] : defines) apply_define(root, k, v, path);
    if (root.contains("frames"))  // no scene key: scenes/*/edits-*.json sit beside the scenes
        c.fail("frames",
               "this is an edits file, not a scene: render it with `latentpt render <fit folder> --edit "
               "<this file>`");
    c.only_keys(root, "", {"integrator", "camera", "materials", "shapes", "emitters"});

    Scene scene;
    scene.file = path;

    read_integrator(c, root, scene.integrator);
    read_camera(c, root, scene.camera);
    const std::map<std::string, int> material_ids = read_materials(c, root, scene);
    read_shapes(c, root, material_ids, scene);
    read_environment(c, root, scene);
    validate_materials(scene);
    scene.build();
    return scene;
}

namespace {
Scene load_scene_by_extension(const std::string& path, const std::map<std::string, std::string>& defines) {
    const std::string ext = lower_extension(path);
    if (ext == ".json") return load_scene_json(path, defines);
    if (ext == ".xml") return load_scene_mitsuba_xml(path, defines);
    throw SceneError(path, "", "unknown scene format '" + ext + "' (known: .json, .xml)");
}
}  // namespace

Scene load_scene(const std::string& path, const std::map<std::string, std::string>& defines,
                 std::optional<SamplerKind> sampler) {
    Scene scene = load_scene_by_extension(path, defines);
    if (sampler) scene.integrator.sampler = *sampler;
    return scene;
}

}  // namespace lpt
