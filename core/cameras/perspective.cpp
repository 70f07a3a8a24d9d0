// Perspective camera: fov (degrees) + fov_axis (x, y, smaller, larger), to_world; pixel filter
// box (radius 0.5) or tent (radius 1). Equations: docs/sampling.md (camera).
#include "core/camera.h"
#include "core/vectorize.h"
#include "core/warp.h"
#include <cmath>

namespace lpt {

Vec2f PixelFilter::sample(const Vec2f& u) const {
    if (type == Type::Box) return Vec2f((2.f * u.x() - 1.f) * radius, (2.f * u.y() - 1.f) * radius);
    return Vec2f(sample_tent(u.x(), radius), sample_tent(u.y(), radius));
}

Vec2f Camera::tan_half_fov() const {
    float t = std::tan(0.5f * fov * kPi / 180.f);
    float aspect = float(width) / float(height);
    bool along_x = fov_axis == FovAxis::X || (fov_axis == FovAxis::Smaller && width <= height) ||
                   (fov_axis == FovAxis::Larger && width >= height);
    return along_x ? Vec2f(t, t / aspect) : Vec2f(t * aspect, t);
}

namespace {

// The ray through film position (fx, fy), shared by generate_ray and the batch so both give
// the same floats. Camera space looks down +z; to_world may scale, so the direction is
// normalised after it. Clip planes are distances along the optical axis (z = 1 in camera
// space): along this ray they are |d_cam| times longer.
inline void camera_ray(float fx, float fy, float width, float height, const Vec2f& th, const Eigen::Matrix4f& m,
                       float near_clip, float far_clip, float& ox, float& oy, float& oz, float& dx, float& dy,
                       float& dz, float& tnear, float& tfar) {
    const float sx = fx / width, sy = fy / height;
    const float cx = (1.f - 2.f * sx) * th.x(), cy = (1.f - 2.f * sy) * th.y();
    const float wx = m(0, 0) * cx + m(0, 1) * cy + m(0, 2);
    const float wy = m(1, 0) * cx + m(1, 1) * cy + m(1, 2);
    const float wz = m(2, 0) * cx + m(2, 1) * cy + m(2, 2);
    const float inv = 1.f / std::sqrt(wx * wx + wy * wy + wz * wz);
    const float len = std::sqrt(cx * cx + cy * cy + 1.f);
    ox = m(0, 3);
    oy = m(1, 3);
    oz = m(2, 3);
    dx = wx * inv;
    dy = wy * inv;
    dz = wz * inv;
    tnear = near_clip * len;
    tfar = far_clip * len;
}

}  // namespace

Ray Camera::generate_ray(const Vec2f& film_pos, const Vec2f& th) const {
    Ray r;
    camera_ray(film_pos.x(), film_pos.y(), float(width), float(height), th, world_from_camera.m, near_clip, far_clip,
               r.o.x(), r.o.y(), r.o.z(), r.d.x(), r.d.y(), r.d.z(), r.tmin, r.tmax);
    return r;
}

namespace {

// One axis of PixelFilter::sample with 0/1 masks instead of selects (GCC does not if-convert
// a square root), exact: x1 and +0 change nothing.
template <bool Tent>
inline float filter_offset(float u, float radius) {
    if constexpr (!Tent) {
        return (2.f * u - 1.f) * radius;
    } else {
        const float left = float(u < 0.5f);
        const float t = std::sqrt(left * (2.f * u) + (1.f - left) * (2.f - 2.f * u));
        return (left * (t - 1.f) + (1.f - left) * (1.f - t)) * radius;
    }
}

// One loop per filter: a branch on the filter inside keeps GCC from vectorising.
template <bool Tent>
inline void camera_rays_for(size_t n, float radius, float width, float height, const Vec2f& th,
                            const Eigen::Matrix4f& m, float near_clip, float far_clip, const float* __restrict px,
                            const float* __restrict py, const float* __restrict u0, const float* __restrict u1,
                            float* __restrict ox, float* __restrict oy, float* __restrict oz, float* __restrict dx,
                            float* __restrict dy, float* __restrict dz, float* __restrict tnear,
                            float* __restrict tfar) {
#pragma GCC ivdep
    for (size_t i = 0; i < n; ++i) {
        const float fx = px[i] + 0.5f + filter_offset<Tent>(u0[i], radius);
        const float fy = py[i] + 0.5f + filter_offset<Tent>(u1[i], radius);
        camera_ray(fx, fy, width, height, th, m, near_clip, far_clip, ox[i], oy[i], oz[i], dx[i], dy[i], dz[i],
                   tnear[i], tfar[i]);
    }
}

LPT_VECTOR_CLONES
void camera_rays(size_t n, bool tent, float radius, float width, float height, const Vec2f th, const Eigen::Matrix4f m,
                 float near_clip, float far_clip, const float* px, const float* py, const float* u0, const float* u1,
                 float* ox, float* oy, float* oz, float* dx, float* dy, float* dz, float* tnear, float* tfar) {
    if (tent)
        camera_rays_for<true>(n, radius, width, height, th, m, near_clip, far_clip, px, py, u0, u1, ox, oy, oz, dx, dy,
                              dz, tnear, tfar);
    else
        camera_rays_for<false>(n, radius, width, height, th, m, near_clip, far_clip, px, py, u0, u1, ox, oy, oz, dx, dy,
                               dz, tnear, tfar);
}

}  // namespace

void Camera::generate_rays(size_t n, const float* px, const float* py, const float* u0, const float* u1,
                           const Vec2f& tan_half, const RayOut& out) const {
    camera_rays(n, filter.type == PixelFilter::Type::Tent, filter.radius, float(width), float(height), tan_half,
                world_from_camera.m, near_clip, far_clip, px, py, u0, u1, out.ox, out.oy, out.oz, out.dx, out.dy,
                out.dz, out.tnear, out.tfar);
}

Camera Camera::with_resolution(int w, int h) const {
    Camera c = *this;
    c.width = w;
    c.height = h;
    return c;
}

}  // namespace lpt
