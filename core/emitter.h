// Emitters: one-sided area lights attached to shapes, a constant environment, and an
// environment map (core/envmap.h). Their
// radiance is spectral data (SceneSpectra<N>); this header holds the geometric part that
// sampling needs, which never depends on learned (signed) radiance. Equations: docs/sampling.md.
#pragma once
#include "core/geometry.h"
#include "core/props.h"
#include "core/shape.h"
#include <memory>

namespace lpt {

enum class EmitterKind { Area, Constant, EnvMap };

class EnvMap;

struct Emitter {
    EmitterKind kind = EmitterKind::Area;
    int shape = -1;  ///< emitting shape (Area only)
    /// As described in the scene file; for an EnvMap its mean radiance over the sphere (light
    /// selection by power, and the latent environment's starting value).
    Eigen::Array3f radiance_rgb = Eigen::Array3f::Ones();
    Props props;                           ///< the description, for error messages and other N
    std::shared_ptr<const EnvMap> envmap;  ///< EnvMap only
    bool is_environment() const { return kind != EmitterKind::Area; }
};

struct LightSample {
    Vec3f p = Vec3f::Zero();    ///< point on the light (Area)
    Vec3f n = Vec3f::UnitZ();   ///< its emission normal
    Vec3f wi = Vec3f::UnitZ();  ///< unit direction from the reference point toward the light
    float dist = kInf;          ///< distance to the light point (inf for the environment)
    float pdf = 0.f;            ///< solid angle at the reference point, light choice included
    int emitter = -1;
    bool valid() const { return pdf > 0.f; }
};

/// An area emitter on shape `shape` from its description (type "area": radiance), as BSDFs are
/// built by make_bsdf; errors name props.file and props.where + the key.
Emitter make_area_emitter(const Props& props, int shape);
/// The environment from its description: type "constant" (radiance) or "envmap" (filename,
/// absolute; scale; to_world). The map is loaded now, so a missing file fails at load time.
Emitter make_environment_emitter(const Props& props);

/// Area light: uniform point on the shape, converted to solid angle at `ref`. Zero pdf when the
/// sample faces away (one-sided emission).
LightSample sample_area_light(const Shape& shape, const Vec3f& ref, const Eigen::Vector3f& u);
/// Solid-angle density of reaching light point p (normal n) from ref by sample_area_light.
float pdf_area_light(const Shape& shape, const Vec3f& ref, const Vec3f& p, const Vec3f& n);
/// Constant environment: uniform sphere of directions.
LightSample sample_constant_light(const Vec2f& u);
float pdf_constant_light();

}  // namespace lpt
