// Mitsuba 3 XML: the camera and how it is rendered. <sensor> (perspective) with its <film>
// (hdrfilm, box or tent rfilter) and <sampler> (the sample count and the nearest sampler we
// have), and <integrator> (path). docs/scene-format.md, "Mitsuba 3 XML".
#include "core/loaders/mitsuba_xml_loader.h"

namespace lpt::mitsuba_xml {

Plugin Loader::read_single(const pugi::xml_node& n, const std::string& tag, bool& seen, const std::string& type) {
    Plugin p = read_plugin(n, tag);
    if (seen) src.fail(n, tag, "only one <" + tag + "> is supported");
    seen = true;
    register_id(p.id, p.tag, p.line);
    if (p.type != type) unknown_plugin(p, type);
    return p;
}

void Loader::read_integrator(const pugi::xml_node& n) {
    Plugin p = read_single(n, "integrator", have_integrator, "path");
    allow_only(p, {"max_depth", "rr_depth", "hide_emitters"});
    for (const pugi::xml_node& c : p.children) unexpected_child(p, c);
    auto& s = scene.integrator;
    s.max_depth = int(get_int(p, "max_depth", -1));
    s.rr_depth = int(get_int(p, "rr_depth", 5));
    if (s.max_depth < -1) fail_value(p, "max_depth", "must be >= -1 (-1: unbounded)");
    if (s.rr_depth < 1) fail_value(p, "rr_depth", "must be >= 1");
    if (get_bool(p, "hide_emitters", false)) fail_value(p, "hide_emitters", "hide_emitters=true is not supported");
}

void Loader::read_sensor(const pugi::xml_node& n) {
    Plugin p = read_single(n, "sensor", have_sensor, "perspective");
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

void Loader::read_film(const pugi::xml_node& n) {
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

void Loader::read_sampler(const pugi::xml_node& n) {
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

}  // namespace lpt::mitsuba_xml
