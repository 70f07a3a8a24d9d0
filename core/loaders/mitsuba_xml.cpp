// Mitsuba 3 XML scenes (docs/scene-format.md, "Mitsuba 3 XML"): the subset the scenes in
// ../shared/scenes use. Every element the loader does not understand is a SceneError naming the
// file and XML line; nothing is silently dropped except <medium> (no participating media here).
// Property parsing, `$name` substitution and transforms are in mitsuba_xml_props.cpp.
#include "core/bsdf.h"
#include "core/loaders/mitsuba_xml_detail.h"
#include "core/loaders/mitsuba_xml_plugin.h"
#include "core/scene_loader.h"
#include "core/shape_factory.h"
#include "core/envmap.h"
#include "core/texture.h"
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace lpt {

namespace fs = std::filesystem;
using namespace mitsuba_xml;

namespace {

struct IdEntry {
    std::string tag;
    int line = -1;
    std::shared_ptr<Props> props;  ///< for <bsdf> and <texture>
    int material = -1;             ///< index in Scene::materials once a shape uses it
};

class Loader : private PluginReader {
public:
    Loader(const Source& src, Scene& scene)
        : PluginReader(src), scene(scene), dir(fs::path(src.path()).parent_path()) {}

    void load(const pugi::xml_node& root) {
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

private:
    Scene& scene;
    fs::path dir;
    std::map<std::string, IdEntry> ids;
    bool have_sensor = false, have_integrator = false;
    int default_material = -1;
    std::vector<int> unnamed_shapes;

    void register_id(const std::string& id, const std::string& tag, int line, std::shared_ptr<Props> props = nullptr) {
        if (id.empty()) return;
        auto [it, fresh] = ids.emplace(id, IdEntry{tag, line, std::move(props), -1});
        if (!fresh)
            src.fail_at(line, "",
                        "duplicate id '" + id + "' (first used by the <" + it->second.tag + "> at line " +
                            std::to_string(it->second.line) + ")");
    }
    IdEntry& resolve_ref(const pugi::xml_node& ref) {
        check_attributes(src, ref, {"id", "name"});
        std::string id = required_attribute(src, ref, "id");
        auto it = ids.find(id);
        if (it == ids.end())
            src.fail(ref, "", "reference to undefined id '" + id + "' (ids must be defined before they are used)");
        return it->second;
    }

    void skip_medium(const pugi::xml_node& n) {
        // Media are ignored (none of our scenes needs one); keep the id so refs to it resolve.
        register_id(n.attribute("id").value(), "medium", src.line(n));
    }

    /// A <texture> as Props (type "bitmap"; filename made absolute, relative to the XML's folder
    /// as Mitsuba resolves it). The image is loaded here, so a missing or unreadable file is
    /// reported at this element's line; the BSDF later gets it from the cache.
    std::shared_ptr<Props> read_texture(const pugi::xml_node& n, const std::string& what) {
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
    /// Top-level <texture id>, for <ref name="reflectance" id="..."/> inside BSDFs (Mitsuba's
    /// named textures).
    void read_top_texture(const pugi::xml_node& n) {
        auto props = read_texture(n, "texture");
        std::string id = n.attribute("id").value();
        if (id.empty())
            src.fail(n, "texture",
                     "a top-level <texture> needs an id (use it with <ref name=\"...\" id=\"...\"/> in a BSDF)");
        register_id(id, "texture", src.line(n), props);
    }
    /// Puts a texture under `name` in a BSDF's props; a name given twice is an error, as for
    /// properties.
    void add_texture(const Plugin& p, Props& props, const pugi::xml_node& c, std::shared_ptr<Props> tex) {
        std::string name = c.attribute("name").value();
        if (name.empty())
            src.fail(c, p.where, "<" + std::string(c.name()) + "> for a texture parameter needs name=\"<parameter>\"");
        if (props.has(name)) src.fail(c, p.where + "." + name, "property '" + name + "' is given twice");
        props.values[name] = std::move(tex);
    }

    Props to_props(const Plugin& p) const {
        Props out;
        out.type = p.type;
        out.file = src.path();
        out.where = p.where + " (line " + std::to_string(p.line) + ")";
        for (const auto& [k, v] : p.values) out.values[k] = v.value;
        return out;
    }

    /// A <bsdf> (nested BSDFs included) as Props, validated by building it for N = 3 so errors
    /// point at the file before rendering starts.
    std::shared_ptr<Props> read_bsdf(const pugi::xml_node& n, const std::string& what) {
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
            make_bsdf<3>(*props);
        } catch (const SceneError& e) {
            // A texture under a key the BSDF reads as a plain colour: say so rather than
            // "expected an rgb triple".
            rethrow_at(src, explain_texture_error(*props, e), p.line);
        }
        if (nested > 0 && p.type != "twosided")
            src.fail(n, p.where, "bsdf '" + p.type + "' does not take a nested BSDF");
        if (nested > 1)
            src.fail(n, p.where, "twosided with a separate back-side BSDF is not supported (give one nested BSDF)");
        register_id(p.id, "bsdf", p.line, props);
        return props;
    }
    int add_material(const Props& m) {
        scene.materials.push_back(m);
        return int(scene.materials.size()) - 1;
    }

    void read_integrator(const pugi::xml_node& n) {
        Plugin p = read_plugin(n, "integrator");
        if (have_integrator) src.fail(n, "integrator", "only one <integrator> is supported");
        have_integrator = true;
        register_id(p.id, p.tag, p.line);
        if (p.type != "path") unknown_plugin(p, "path");
        allow_only(p, {"max_depth", "rr_depth", "hide_emitters"});
        for (const pugi::xml_node& c : p.children) unexpected_child(p, c);
        auto& s = scene.integrator;
        s.max_depth = int(get_int(p, "max_depth", -1));
        s.rr_depth = int(get_int(p, "rr_depth", 5));
        if (s.max_depth < -1) fail_value(p, "max_depth", "must be >= -1 (-1: unbounded)");
        if (s.rr_depth < 1) fail_value(p, "rr_depth", "must be >= 1");
        if (get_bool(p, "hide_emitters", false)) fail_value(p, "hide_emitters", "hide_emitters=true is not supported");
    }

    void read_sensor(const pugi::xml_node& n) {
        Plugin p = read_plugin(n, "sensor");
        if (have_sensor) src.fail(n, "sensor", "only one <sensor> is supported");
        have_sensor = true;
        register_id(p.id, p.tag, p.line);
        if (p.type != "perspective") unknown_plugin(p, "perspective");
        // focus_distance only matters to thinlens; a pinhole ignores it as Mitsuba's perspective does.
        allow_only(p, {"fov", "fov_axis", "near_clip", "far_clip", "to_world", "focus_distance"});
        Camera& cam = scene.camera;
        if (!p.find("fov"))
            src.fail_at(p.line, p.where + ".fov",
                        "perspective sensor needs 'fov' in degrees (focal_length is not supported)");
        cam.fov = get_float(p, "fov", 45.f);
        if (!(cam.fov > 0.f && cam.fov < 180.f)) fail_value(p, "fov", "must be in (0, 180) degrees");
        std::string axis = get_string(p, "fov_axis", "x");
        if (axis == "x") cam.fov_axis = FovAxis::X;
        else if (axis == "y") cam.fov_axis = FovAxis::Y;
        else if (axis == "smaller") cam.fov_axis = FovAxis::Smaller;
        else if (axis == "larger") cam.fov_axis = FovAxis::Larger;
        else if (axis == "diagonal")
            fail_value(p, "fov_axis", "fov_axis 'diagonal' is not supported (use x, y, smaller or larger)");
        else fail_value(p, "fov_axis", "expected x, y, smaller, larger or diagonal, got '" + axis + "'");
        cam.near_clip = get_float(p, "near_clip", 1e-2f);
        cam.far_clip = get_float(p, "far_clip", 1e4f);
        if (!(cam.near_clip > 0.f)) fail_value(p, "near_clip", "must be > 0");
        if (!(cam.far_clip > cam.near_clip)) fail_value(p, "far_clip", "must be > near_clip");
        // Mitsuba's camera frame is ours (+z forward, +y up, +x left), so to_world is used as is.
        // Like Mitsuba, refuse scale: it would silently change the field of view.
        cam.world_from_camera = get_transform(p, "to_world");
        Eigen::Matrix3f r = cam.world_from_camera.m.topLeftCorner<3, 3>();
        if (!(r.transpose() * r).isIdentity(1e-3f))
            fail_value(p, "to_world", "camera to_world must not scale or shear (Mitsuba rejects it too)");

        bool have_film = false;
        for (const pugi::xml_node& c : p.children) {
            const std::string tag = c.name();
            if (tag == "film") {
                if (have_film) src.fail(c, "film", "only one <film> is supported");
                have_film = true;
                read_film(c);
            } else if (tag == "sampler") read_sampler(c);
            else if (tag == "medium") skip_medium(c);
            else if (tag == "ref" && resolve_ref(c).tag == "medium") continue;
            else unexpected_child(p, c);
        }
        // Mitsuba's default film filters with a gaussian, which we cannot reproduce.
        if (!have_film)
            src.fail_at(p.line, "film",
                        "sensor has no <film>: Mitsuba's default uses a gaussian rfilter, which is unsupported; add "
                        "<film type=\"hdrfilm\"> with <rfilter type=\"box\"/> or \"tent\"");
    }

    void read_film(const pugi::xml_node& n) {
        Plugin p = read_plugin(n, "film");
        if (p.type != "hdrfilm") unknown_plugin(p, "hdrfilm");
        // Output-format settings: our writer always produces float RGB EXR.
        allow_only(p, {"width", "height", "pixel_format", "component_format", "file_format"});
        long long w = get_int(p, "width", 768), h = get_int(p, "height", 576);  // Mitsuba's defaults
        if (w < 1) fail_value(p, "width", "must be >= 1");
        if (h < 1) fail_value(p, "height", "must be >= 1");
        scene.camera.width = int(w);
        scene.camera.height = int(h);
        bool have_filter = false;
        for (const pugi::xml_node& c : p.children) {
            if (std::string(c.name()) != "rfilter") unexpected_child(p, c);
            if (have_filter) src.fail(c, "rfilter", "only one <rfilter> is supported");
            have_filter = true;
            Plugin f = read_plugin(c, "rfilter");
            PixelFilter& pf = scene.camera.filter;
            if (f.type == "box") pf = {PixelFilter::Type::Box, 0.5f};
            else if (f.type == "tent") pf = {PixelFilter::Type::Tent, 1.f};
            else if (f.type == "gaussian")
                src.fail_at(f.line, "rfilter.type", "rfilter 'gaussian' is unsupported, use box or tent");
            else unknown_plugin(f, "box, tent");
            allow_only(f, {"radius"});
            for (const pugi::xml_node& cc : f.children) unexpected_child(f, cc);
            pf.radius = get_float(f, "radius", pf.radius);
            if (!(pf.radius > 0.f)) fail_value(f, "radius", "must be > 0");
        }
        if (!have_filter)
            src.fail_at(p.line, "rfilter",
                        "film has no <rfilter>: Mitsuba's default is gaussian, which is unsupported, use box or tent");
    }

    void read_sampler(const pugi::xml_node& n) {
        Plugin p = read_plugin(n, "sampler");
        // The sample count, and the nearest sampler we have (docs/sampling.md): `independent` stays
        // independent, every stratified or low-discrepancy Mitsuba sampler becomes Owen-scrambled
        // Sobol. Its seed, jitter and strength change noise, not the expected image.
        if (p.type == "independent") scene.integrator.sampler = SamplerKind::Independent;
        else if (p.type == "stratified" || p.type == "multijitter" || p.type == "ldsampler" || p.type == "orthogonal")
            scene.integrator.sampler = SamplerKind::Sobol;
        else unknown_plugin(p, "independent, stratified, multijitter, ldsampler, orthogonal");
        allow_only(p, {"sample_count", "seed", "jitter", "strength"});
        for (const pugi::xml_node& c : p.children) unexpected_child(p, c);
        long long spp = get_int(p, "sample_count", 4);
        if (spp < 1) fail_value(p, "sample_count", "must be >= 1");
        scene.integrator.spp = int(spp);
    }

    void read_top_emitter(const pugi::xml_node& n) {
        Plugin p = read_plugin(n, "emitter");
        if (p.type == "area")
            src.fail_at(p.line, p.where + ".type", "an 'area' emitter must be nested inside a <shape>");
        if (p.type != "constant" && p.type != "envmap") unknown_plugin(p, "area (inside a shape), constant, envmap");
        if (scene.environment >= 0) src.fail_at(p.line, p.where, "only one environment emitter is supported");
        Emitter e = p.type == "envmap" ? read_envmap(p) : read_emitter_props(p, EmitterKind::Constant, -1);
        register_id(p.id, p.tag, p.line);
        scene.environment = int(scene.emitters.size());
        scene.emitters.push_back(e);
    }
    /// Mitsuba 3 envmap: filename (relative to the XML), scale, to_world. The image is loaded
    /// now, so a missing file is an error at the emitter's line naming the file.
    Emitter read_envmap(const Plugin& p) {
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

    Emitter read_emitter_props(const Plugin& p, EmitterKind kind, int shape) {
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

    /// A shape's properties checked against what its type takes, each of its XML kind (a wrong
    /// kind is an error at its line), as the Props make_shape reads; the filename relative to
    /// the XML's folder, as Mitsuba resolves it.
    Props shape_props(const Plugin& p) const {
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

    void read_shape(const pugi::xml_node& n) {
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

    /// Unnamed shapes get "shape_<index>", suffixed until unique: our ids must be unique, while
    /// Mitsuba lets shapes go without one.
    void name_unnamed_shapes() {
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
};

}  // namespace

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
