// Area emitter ("area", key radiance: rgb, W m^-2 sr^-1): emits on the side of the shape's
// normal only. Sampled uniformly by area; docs/sampling.md (4) converts to solid angle.
#include "core/emitter.h"

namespace lpt {

LightSample sample_area_light(const Shape& shape, const Vec3f& ref, const Eigen::Vector3f& u) {
    PositionSample ps = shape.sample_position(u);
    LightSample ls;
    Vec3f d = ps.p - ref;
    float dist2 = d.squaredNorm();
    if (dist2 <= 0.f) return ls;
    ls.dist = std::sqrt(dist2);
    ls.wi = d * (1.f / ls.dist);
    ls.p = ps.p;
    ls.n = ps.n;
    float cos_l = -ls.wi.dot(ps.n);
    if (cos_l <= 0.f) return ls;  // back side: one-sided emission contributes nothing
    ls.pdf = ps.pdf_area * dist2 / cos_l;
    return ls;
}

float pdf_area_light(const Shape& shape, const Vec3f& ref, const Vec3f& p, const Vec3f& n) {
    Vec3f d = p - ref;
    float dist2 = d.squaredNorm();
    float cos_l = -d.dot(n) / std::sqrt(dist2);
    if (cos_l <= 0.f) return 0.f;
    return dist2 / (cos_l * shape.area());
}

}  // namespace lpt
