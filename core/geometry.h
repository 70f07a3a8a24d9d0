// Vectors, rays and orthonormal frames. Directions in a Frame's local coordinates have the
// normal along +z (Nori/Mitsuba convention), so cos θ is just .z().
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>

namespace lpt {

using Vec2f = Eigen::Vector2f;
using Vec3f = Eigen::Vector3f;
using Vec2i = Eigen::Vector2i;

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInf = std::numeric_limits<float>::infinity();
/// Relative offset for spawning secondary rays; scaled by the hit position's magnitude.
constexpr float kRayEpsilon = 1e-4f;

struct Ray {
    Vec3f o = Vec3f::Zero();
    Vec3f d = Vec3f::UnitZ();
    float tmin = 0.f;
    float tmax = kInf;
};

/// Orthonormal basis around n (Duff et al. 2017, branchless).
struct Frame {
    Vec3f s, t, n;
    Frame() : s(Vec3f::UnitX()), t(Vec3f::UnitY()), n(Vec3f::UnitZ()) {}
    explicit Frame(const Vec3f& normal) : n(normal) {
        float sign = std::copysign(1.f, n.z());
        float a = -1.f / (sign + n.z());
        float b = n.x() * n.y() * a;
        s = Vec3f(1.f + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
        t = Vec3f(b, sign + n.y() * n.y() * a, -n.y());
    }
    Vec3f to_local(const Vec3f& v) const { return Vec3f(v.dot(s), v.dot(t), v.dot(n)); }
    Vec3f to_world(const Vec3f& v) const { return s * v.x() + t * v.y() + n * v.z(); }
};

inline float cos_theta(const Vec3f& w) { return w.z(); }
inline float abs_cos_theta(const Vec3f& w) { return std::abs(w.z()); }

/// Offset a ray origin off a surface along the geometric normal, on the side of `dir`.
inline Vec3f offset_ray_origin(const Vec3f& p, const Vec3f& ng, const Vec3f& dir) {
    float scale = kRayEpsilon * std::max(1.f, p.cwiseAbs().maxCoeff());
    return p + (ng.dot(dir) >= 0.f ? scale : -scale) * ng;
}

}  // namespace lpt
