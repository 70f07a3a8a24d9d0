// Mitsuba 3 XML scenes (docs/scene-format.md, "Mitsuba 3 XML"): the subset the scenes in
// ../shared/scenes use. Every element the loader does not understand is a SceneError naming the
// file and XML line; nothing is silently dropped except <medium> (no participating media here).
// Property parsing, `$name` substitution and transforms are in mitsuba_xml_props.cpp, the sensor,
// film, sampler and integrator in mitsuba_xml_sensor.cpp.
#include "core/bsdf.h"
#include "core/loaders/mitsuba_xml_loader.h"
#include "core/scene_loader.h"
#include "core/shape_factory.h"
#include "core/envmap.h"
#include "core/texture.h"
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace lpt {

namespace mitsuba_xml {

void Loader::load(const pugi::xml_node& root) {
    for (pugi::xml_node c : root.children()) {
        if (c.type() != pugi::node_element) continue;
        const std::string tag = c.name();
        if (tag == "default") continue;  // consumed by substitute_parameters
        else if (tag == "integrator") read_integrator(c);
        else if (tag == "sensor") read_sensor(c);
        else if (tag == "bsdf") read_bsdf(c, "bsdf");
        else if (tag == "shape") read_shape(c);
        else if (tag == "emitter") read_top_emitter(c);
        else if (tag == "texture") read_top_texture(c);
        else if (tag == "medium") skip_medium(c);
        else
            src.fail(c, "",
                     "<" + tag +
                         "> is not supported at the top level of <scene> (known: default, integrator, sensor, "
                         "bsdf, texture, shape, emitter)");
    }
    if (!have_sensor) src.fail(root, "sensor", "scene has no <sensor>");
    if (scene.shapes.empty()) src.fail(root, "shape", "scene has no <shape>");
    name_unnamed_shapes();
}

void Loader::register_id(const std::string& id, const std::string& tag, int line, std::shared_ptr<Props> props) {
    if (id.empty()) return;
    auto [it, fresh] = ids.emplace(id, IdEntry{tag, line, std::move(props), -1});
    if (!fresh)
        src.fail_at(line, "",
                    "duplicate id '" + id + "' (first used by the <" + it->second.tag + "> at line " +
                        std::to_string(it->second.line) + ")");
}

IdEntry& Loader::resolve_ref(const pugi::xml_node& ref) {
    check_attributes(src, ref, {"id", "name"});
    std::string id = required_attribute(src, ref, "id");
    auto it = ids.find(id);
    if (it == ids.end())
        src.fail(ref, "", "reference to undefined id '" + id + "' (ids must be defined before they are used)");
    return it->second;
}

void Loader::skip_medium(const pugi::xml_node& n) {
    // Media are ignored (none of our scenes needs one); keep the id so refs to it resolve.
    register_id(n.attribute("id").value(), "medium", src.line(n));
}

std::shared_ptr<Props> Loader::read_texture(const pugi::xml_node& n, const std::string& what) {
    Plugin p = read_plugin(n, what);
    if (p.type != "bitmap")
        src.fail_at(p.line, p.where + ".type", "unknown texture plugin '" + p.type + "' (known: bitmap)");
    if (p.find("to_uv")) fail_value(p, "to_uv", "to_uv is not supported yet (uvs are used as they are)");
    allow_only(p, {"filename", "raw", "filter_type", "wrap_mode"});
    for (const pugi::xml_node& c : p.children) unexpected_child(p, c);
    if (!p.find("filename")) src.fail_at(p.line, p.where + ".filename", "a bitmap texture needs a filename");
    std::string filter = get_string(p, "filter_type", "bilinear"), wrap = get_string(p, "wrap_mode", "repeat");
    if (filter != "bilinear" && filter != "nearest")
        fail_value(p, "filter_type", "expected bilinear or nearest, got '" + filter + "'");
    if (wrap != "repeat" && wrap != "mirror" && wrap != "clamp")
        fail_value(p, "wrap_mode", "expected repeat, mirror or clamp, got '" + wrap + "'");
    const bool raw = get_bool(p, "raw", false);
    std::string file = fs::absolute(dir / get_string(p, "filename", "")).lexically_normal().string();
    try {
        Texture::load_bitmap(file, raw);
    } catch (const SceneError& e) {
        fail_value(p, "filename", e.what());
    }
    auto props = std::make_shared<Props>(to_props(p));
    props->values["filename"] = file;
    return props;
}

void Loader::read_top_texture(const pugi::xml_node& n) {
    auto props = read_texture(n, "texture");
    std::string id = n.attribute("id").value();
    if (id.empty())
        src.fail(n, "texture",
                 "a top-level <texture> needs an id (use it with <ref name=\"...\" id=\"...\"/> in a BSDF)");
    register_id(id, "texture", src.line(n), props);
}

void Loader::add_texture(const Plugin& p, Props& props, const pugi::xml_node& c, std::shared_ptr<Props> tex) {
    std::string name = c.attribute("name").value();
    if (name.empty())
        src.fail(c, p.where, "<" + std::string(c.name()) + "> for a texture parameter needs name=\"<parameter>\"");
    if (props.has(name)) src.fail(c, p.where + "." + name, "property '" + name + "' is given twice");
    props.values[name] = std::move(tex);
}

Props Loader::to_props(const Plugin& p) const {
    Props out;
    out.type = p.type;
    out.file = src.path();
    out.where = p.where + " (line " + std::to_string(p.line) + ")";
    for (const auto& [k, v] : p.values) out.values[k] = v.value;
    return out;
}

std::shared_ptr<Props> Loader::read_bsdf(const pugi::xml_node& n, const std::string& what) {
    Plugin p = read_plugin(n, what);
    auto props = std::make_shared<Props>(to_props(p));
    int nested = 0;
    for (const pugi::xml_node& c : p.children) {
        const std::string tag = c.name();
        std::shared_ptr<Props> child;
        if (tag == "bsdf") child = read_bsdf(c, p.where + ".bsdf");
        else if (tag == "ref") {
            IdEntry& e = resolve_ref(c);
            if (e.tag == "texture") {
                add_texture(p, *props, c, e.props);
                continue;
            }
            if (e.tag != "bsdf")
                src.fail(c, p.where,
                         "ref '" + std::string(c.attribute("id").value()) + "' names a <" + e.tag +
                             ">, expected a <bsdf> or <texture>");
            child = e.props;
        } else if (tag == "texture") {
            add_texture(p, *props, c, read_texture(c, p.where + "." + c.attribute("name").value()));
            continue;
        } else unexpected_child(p, c);
        if (++nested == 1) props->values["bsdf"] = child;
    }
    try {
        check_bsdf_description(*props);
    } catch (const SceneError& e) {
        rethrow_at(src, e, p.line);
    }
    if (nested > 0 && p.type != "twosided") src.fail(n, p.where, "bsdf '" + p.type + "' does not take a nested BSDF");
    if (nested > 1)
        src.fail(n, p.where, "twosided with a separate back-side BSDF is not supported (give one nested BSDF)");
    register_id(p.id, "bsdf", p.line, props);
    return props;
}

int Loader::add_material(const Props& m) {
    scene.materials.push_back(m);
    return int(scene.materials.size()) - 1;
}

void Loader::read_top_emitter(const pugi::xml_node& n) {
    Plugin p = read_plugin(n, "emitter");
    if (p.type == "area") src.fail_at(p.line, p.where + ".type", "an 'area' emitter must be nested inside a <shape>");
    if (p.type != "constant" && p.type != "envmap") unknown_plugin(p, "area (inside a shape), constant, envmap");
    if (scene.environment >= 0) src.fail_at(p.line, p.where, "only one environment emitter is supported");
    Emitter e = p.type == "envmap" ? read_envmap(p) : read_emitter_props(p, EmitterKind::Constant, -1);
    register_id(p.id, p.tag, p.line);
    scene.environment = int(scene.emitters.size());
    scene.emitters.push_back(e);
}

Emitter Loader::read_envmap(const Plugin& p) {
    allow_only(p, {"filename", "scale", "to_world"});
    for (const pugi::xml_node& c : p.children) unexpected_child(p, c);
    const std::string name = get_string(p, "filename", "");
    if (name.empty()) src.fail_at(p.line, p.where + ".filename", "missing");
    get_float(p, "scale", 1.f);
    get_transform(p, "to_world");
    Props props = to_props(p);
    props.values["filename"] = fs::absolute(dir / name).lexically_normal().string();
    try {
        return make_environment_emitter(props);
    } catch (const SceneError& err) {
        fail_value(p, "filename",
                   err.message() + " (the environment map; see the scene's SOURCE/README for where to get it)");
    }
}

Emitter Loader::read_emitter_props(const Plugin& p, EmitterKind kind, int shape) {
    allow_only(p, {"radiance"});
    for (const pugi::xml_node& c : p.children) {
        if (std::string(c.name()) == "texture") fail_texture(p, c);
        unexpected_child(p, c);
    }
    try {
        return kind == EmitterKind::Area ? make_area_emitter(to_props(p), shape)
                                         : make_environment_emitter(to_props(p));
    } catch (const SceneError& err) {
        rethrow_at(src, err, p.line);
    }
}

Props Loader::shape_props(const Plugin& p) const {
    const std::string& t = p.type;
    if (t == "obj") allow_only(p, {"filename", "face_normals", "flip_tex_coords", "flip_normals", "to_world"});
    else if (t == "ply") allow_only(p, {"filename", "face_normals", "flip_normals", "to_world"});
    else if (t == "rectangle" || t == "cube") allow_only(p, {"flip_normals", "to_world"});
    else if (t == "sphere") allow_only(p, {"center", "radius", "flip_normals", "to_world"});
    else unknown_plugin(p, "obj, ply, rectangle, cube, sphere");
    if ((t == "obj" || t == "ply") && !p.find("filename")) src.fail_at(p.line, p.where + ".filename", "missing");
    Props out;
    out.type = t;
    out.file = src.path();
    out.where = p.where;
    if (p.find("filename")) out.values["filename"] = (dir / get_string(p, "filename", "")).string();
    for (const char* key : {"face_normals", "flip_tex_coords", "flip_normals"})
        if (p.find(key)) out.values[key] = get_bool(p, key, false);
    if (p.find("radius")) out.values["radius"] = get_float(p, "radius", 1.f);
    if (p.find("center")) out.values["center"] = Eigen::Array3f(get_point(p, "center", Vec3f::Zero()).array());
    if (p.find("to_world")) out.values["to_world"] = get_transform(p, "to_world");
    return out;
}

void Loader::read_shape(const pugi::xml_node& n) {
    Plugin p = read_plugin(n, "shape");
    const Props props = shape_props(p);
    Shape shape;
    try {
        shape = make_shape(props, kMitsubaShapeDefaults);
    } catch (const SceneError& e) {
        rethrow_at(src, e, line_of(p, e.field()));
    }
    shape.id = p.id;
    const int index = int(scene.shapes.size());
    for (const pugi::xml_node& c : p.children) {
        const std::string tag = c.name();
        if (tag == "bsdf" || tag == "ref") {
            int material = -1;
            if (tag == "bsdf") {
                auto props = read_bsdf(c, p.where + ".bsdf");
                material = add_material(*props);
                if (c.attribute("id")) ids[c.attribute("id").value()].material = material;  // later refs share it
            } else {
                IdEntry& e = resolve_ref(c);
                if (e.tag == "medium") continue;  // interior/exterior media are ignored
                if (e.tag != "bsdf")
                    src.fail(c, p.where,
                             "ref '" + std::string(c.attribute("id").value()) + "' names a <" + e.tag +
                                 ">; a shape takes a <bsdf>");
                if (e.material < 0) e.material = add_material(*e.props);
                material = e.material;
            }
            if (shape.material >= 0) src.fail(c, p.where, "shape has more than one BSDF");
            shape.material = material;
        } else if (tag == "emitter") {
            Plugin ep = read_plugin(c, p.where + ".emitter");
            if (ep.type != "area")
                src.fail_at(ep.line, ep.where + ".type", "a shape's emitter must be 'area', got '" + ep.type + "'");
            if (shape.emitter >= 0) src.fail(c, p.where, "shape has more than one emitter");
            Emitter e = read_emitter_props(ep, EmitterKind::Area, index);
            register_id(ep.id, ep.tag, ep.line);
            shape.emitter = int(scene.emitters.size());
            scene.emitters.push_back(e);
        } else if (tag == "medium") {
            skip_medium(c);
        } else if (tag == "texture") {
            fail_texture(p, c);
        } else {
            unexpected_child(p, c);
        }
    }
    if (shape.material < 0) {  // Mitsuba's default BSDF
        if (default_material < 0) {
            Props d;
            d.type = "diffuse";
            d.file = src.path();
            d.where = "default bsdf";
            d.values["reflectance"] = 0.5f;
            default_material = add_material(d);
        }
        shape.material = default_material;
    }
    register_id(p.id, p.tag, p.line);
    if (p.id.empty()) unnamed_shapes.push_back(index);
    scene.shapes.push_back(std::move(shape));
}

void Loader::name_unnamed_shapes() {
    std::set<std::string> used;
    for (const Shape& s : scene.shapes)
        if (!s.id.empty()) used.insert(s.id);
    for (int i : unnamed_shapes) {
        std::string base = "shape_" + std::to_string(i), id = base;
        for (int k = 2; used.count(id); ++k) id = base + "_" + std::to_string(k);
        used.insert(id);
        scene.shapes[i].id = id;
    }
}

}  // namespace mitsuba_xml

using namespace mitsuba_xml;

Scene load_scene_mitsuba_xml(const std::string& path, const std::map<std::string, std::string>& defines) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw SceneError(path, "", "cannot open file");
    std::stringstream ss;
    ss << in.rdbuf();
    Source src(path, ss.str());

    pugi::xml_document doc;
    pugi::xml_parse_result parsed = doc.load_buffer(src.text().data(), src.text().size());
    if (!parsed)
        throw SceneError(path, "", std::string("malformed XML: ") + parsed.description(),
                         src.line_of_offset(parsed.offset));
    pugi::xml_node root = doc.document_element();
    if (std::string(root.name()) != "scene")
        src.fail(root, "", "the root element must be <scene>, got <" + std::string(root.name()) + ">");

    substitute_parameters(src, root, defines);
    check_attributes(src, root, {"version"});
    std::string version = required_attribute(src, root, "version");
    int major = -1;
    try {
        major = std::stoi(version);
    } catch (const std::exception&) {
        src.fail(root, "version", "cannot read scene version '" + version + "'");
    }
    if (major < 2)
        src.fail(root, "version",
                 "scene version " + version +
                     " is a Mitsuba 0.x file (camelCase names such as toWorld, sampleCount); only versions 2.x and 3.x "
                     "are supported");
    if (major > 3) src.fail(root, "version", "scene version " + version + " is not supported (2.x or 3.x)");

    Scene scene;
    scene.file = path;
    // Mitsuba's defaults where the file is silent: path tracer without a depth limit, and the
    // 4 samples per pixel of its default sampler.
    scene.integrator.max_depth = -1;
    scene.integrator.rr_depth = 5;
    scene.integrator.spp = 4;
    Loader(src, scene).load(root);
    scene.build();
    return scene;
}

}  // namespace lpt
