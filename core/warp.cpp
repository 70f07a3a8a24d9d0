#include "core/warp.h"
#include <algorithm>

namespace lpt {

Vec3f sample_uniform_sphere(const Vec2f& u) {
    float z = 1.f - 2.f * u.x();
    float r = std::sqrt(std::max(0.f, 1.f - z * z));
    float phi = 2.f * kPi * u.y();
    return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
}

float pdf_uniform_sphere(const Vec3f&) { return 0.25f * kInvPi; }

float pdf_tent(float x, float radius) {
    float t = std::abs(x) / radius;
    return t < 1.f ? (1.f - t) / radius : 0.f;
}

}  // namespace lpt
