// Emitters built from their descriptions (Props); the scene loaders only translate syntax.
#include "core/emitter.h"
#include "core/envmap.h"

namespace lpt {

Emitter make_area_emitter(const Props& props, int shape) {
    if (props.type != "area") props.fail("type", "a shape's emitter must be 'area', got '" + props.type + "'");
    Emitter e;
    e.kind = EmitterKind::Area;
    e.shape = shape;
    e.radiance_rgb = props.get_colour("radiance");
    e.props = props;
    return e;
}

Emitter make_environment_emitter(const Props& props) {
    Emitter e;
    e.props = props;
    if (props.type == "constant") {
        e.kind = EmitterKind::Constant;
        e.radiance_rgb = props.get_colour("radiance");
        return e;
    }
    if (props.type != "envmap")
        props.fail("type", "unknown environment emitter '" + props.type + "' (known: constant, envmap)");
    const std::string file = props.get_string("filename", "");
    if (file.empty()) props.fail("filename", "missing");
    try {
        e.envmap = EnvMap::load(file, props.get_transform("to_world", Transform()), props.get_float("scale", 1.f));
    } catch (const SceneError& err) {
        props.fail("filename", err.what());
    }
    e.kind = EmitterKind::EnvMap;
    e.radiance_rgb = e.envmap->mean_radiance();
    return e;
}

}  // namespace lpt
