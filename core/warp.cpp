#include "core/warp.h"
#include "core/vectorize.h"
#include <algorithm>

namespace lpt {

Vec3f sample_uniform_sphere(const Vec2f& u) {
    float z = 1.f - 2.f * u.x();
    float r = std::sqrt(std::max(0.f, 1.f - z * z));
    float phi = 2.f * kPi * u.y();
    return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
}

float pdf_uniform_sphere(const Vec3f&) { return 0.25f * kInvPi; }

// m in {0, 1} blends exactly (products with 0 and 1 and sums with 0 are exact, up to the sign
// of a zero), so every lane gives the float of sample_uniform_disk_concentric's taken branch.
LPT_VECTOR_CLONES
void sample_cosine_hemisphere_batch(const float* __restrict u0, const float* __restrict u1, float* __restrict x_out,
                                    float* __restrict y_out, float* __restrict z_out, size_t n) {
    for (size_t i = 0; i < n; ++i) {
        const float x = 2.f * u0[i] - 1.f, y = 2.f * u1[i] - 1.f;
        const float m = float(std::abs(x) > std::abs(y));
        const float r = m * x + (1.f - m) * y, other = m * y + (1.f - m) * x;
        float s, c;
        sincos_quarter_pi(0.25f * kPi * (other / (r + float(r == 0.f))), s, c);
        const float dx = r * (m * c + (1.f - m) * s), dy = r * (m * s + (1.f - m) * c);
        x_out[i] = dx;
        y_out[i] = dy;
        z_out[i] = std::sqrt(std::max(0.f, 1.f - (dx * dx + dy * dy)));
    }
}

float pdf_tent(float x, float radius) {
    float t = std::abs(x) / radius;
    return t < 1.f ? (1.f - t) / radius : 0.f;
}

}  // namespace lpt
