#include "core/warp.h"
#include <algorithm>

namespace lpt {

Vec2f sample_uniform_disk_concentric(const Vec2f& u) {
    float x = 2.f * u.x() - 1.f, y = 2.f * u.y() - 1.f;
    if (x == 0.f && y == 0.f) return Vec2f::Zero();
    float r, theta;
    if (std::abs(x) > std::abs(y)) {
        r = x;
        theta = 0.25f * kPi * (y / x);
    } else {
        r = y;
        theta = 0.5f * kPi - 0.25f * kPi * (x / y);
    }
    return Vec2f(r * std::cos(theta), r * std::sin(theta));
}

Vec3f sample_cosine_hemisphere(const Vec2f& u) {
    Vec2f d = sample_uniform_disk_concentric(u);
    float z = std::sqrt(std::max(0.f, 1.f - d.squaredNorm()));
    return Vec3f(d.x(), d.y(), z);
}

float pdf_cosine_hemisphere(const Vec3f& w) { return w.z() > 0.f ? w.z() * kInvPi : 0.f; }

Vec3f sample_uniform_sphere(const Vec2f& u) {
    float z = 1.f - 2.f * u.x();
    float r = std::sqrt(std::max(0.f, 1.f - z * z));
    float phi = 2.f * kPi * u.y();
    return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
}

float pdf_uniform_sphere(const Vec3f&) { return 0.25f * kInvPi; }

Vec2f sample_uniform_triangle(const Vec2f& u) {
    float su = std::sqrt(u.x());
    return Vec2f(1.f - su, u.y() * su);
}

float sample_tent(float u, float radius) {
    // Invert the CDF of the triangle density on [-1, 1], then scale.
    float x = u < 0.5f ? std::sqrt(2.f * u) - 1.f : 1.f - std::sqrt(2.f - 2.f * u);
    return x * radius;
}

float pdf_tent(float x, float radius) {
    float t = std::abs(x) / radius;
    return t < 1.f ? (1.f - t) / radius : 0.f;
}

}  // namespace lpt
