// Perspective camera: fov (degrees) + fov_axis (x, y, smaller, larger), to_world; pixel filter
// box (radius 0.5) or tent (radius 1). Equations: docs/sampling.md (camera).
#include "core/camera.h"
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

Ray Camera::generate_ray(const Vec2f& film_pos, const Vec2f& th) const {
    float sx = film_pos.x() / float(width), sy = film_pos.y() / float(height);
    Vec3f d_cam((1.f - 2.f * sx) * th.x(), (1.f - 2.f * sy) * th.y(), 1.f);
    Ray r;
    r.o = world_from_camera.m.topRightCorner<3, 1>();
    const Vec3f d = world_from_camera.vector(d_cam);  // to_world may scale: normalise after it
    r.d = d * (1.f / d.norm());
    // Clip planes are distances along the optical axis (z = 1 in d_cam): along this ray they
    // are |d_cam| times longer.
    const float len = d_cam.norm();
    r.tmin = near_clip * len;
    r.tmax = far_clip * len;
    return r;
}

Camera Camera::with_resolution(int w, int h) const {
    Camera c = *this;
    c.width = w;
    c.height = h;
    return c;
}

}  // namespace lpt
