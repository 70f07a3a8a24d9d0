// Warps from [0,1)^2 to sampling domains, each paired with its pdf by a shared stem
// (sample_X / pdf_X). Equations: docs/sampling.md.
#pragma once
#include "core/geometry.h"
#include <algorithm>
#include <cmath>
#include <cstddef>

namespace lpt {

// The warps every path vertex uses are inline: the tracer calls them per sample from another
// library, where an out-of-line call also blocks vectorising the surrounding stage.

/// sin a and cos a for |a| <= π/4 from their Taylor series up to a^11 and a^10 (truncation
/// < 3e-9, below float rounding; tests/core/test_warp.cpp). The concentric map only ever needs
/// such angles, and libm's sincosf was ~9% of a Cornell box render (docs/performance.md).
inline void sincos_quarter_pi(float a, float& s, float& c) {
    const float a2 = a * a;
    s = a * (1.f + a2 * (-1.f / 6.f +
                         a2 * (1.f / 120.f + a2 * (-1.f / 5040.f + a2 * (1.f / 362880.f + a2 * (-1.f / 39916800.f))))));
    c = 1.f + a2 * (-0.5f + a2 * (1.f / 24.f + a2 * (-1.f / 720.f + a2 * (1.f / 40320.f + a2 * (-1.f / 3628800.f)))));
}

/// Shirley–Chiu concentric map (docs/sampling.md): the angle within each octant is π/4·(ratio).
inline Vec2f sample_uniform_disk_concentric(const Vec2f& u) {
    const float x = 2.f * u.x() - 1.f, y = 2.f * u.y() - 1.f;
    if (x == 0.f && y == 0.f) return Vec2f::Zero();
    float s, c;
    if (std::abs(x) > std::abs(y)) {
        sincos_quarter_pi(0.25f * kPi * (y / x), s, c);
        return Vec2f(x * c, x * s);
    }
    // θ = π/2 − a: cos θ = sin a, sin θ = cos a.
    sincos_quarter_pi(0.25f * kPi * (x / y), s, c);
    return Vec2f(y * s, y * c);
}

inline Vec3f sample_cosine_hemisphere(const Vec2f& u) {
    const Vec2f d = sample_uniform_disk_concentric(u);
    return Vec3f(d.x(), d.y(), std::sqrt(std::max(0.f, 1.f - d.squaredNorm())));
}

/// sample_cosine_hemisphere for n sample pairs at once, the same floats (tests/core/test_warp.cpp): written with
/// arithmetic selects so the compiler evaluates it 4 or 8 wide. The per-vertex warp is a long
/// dependent chain (division, polynomial, square root) that one vertex at a time leaves the
/// CPU waiting on; the tracer warps its whole shade queue with this instead.
void sample_cosine_hemisphere_batch(const float* u0, const float* u1, float* x, float* y, float* z, size_t n);

inline float pdf_cosine_hemisphere(const Vec3f& w) { return w.z() > 0.f ? w.z() * kInvPi : 0.f; }

Vec3f sample_uniform_sphere(const Vec2f& u);
float pdf_uniform_sphere(const Vec3f& w);

/// Barycentrics (b1, b2) uniform over a triangle.
inline Vec2f sample_uniform_triangle(const Vec2f& u) {
    const float su = std::sqrt(u.x());
    return Vec2f(1.f - su, u.y() * su);
}

/// Tent filter of radius r on [-r, r]: triangle-shaped density (inverted CDF, then scaled).
inline float sample_tent(float u, float radius) {
    const float x = u < 0.5f ? std::sqrt(2.f * u) - 1.f : 1.f - std::sqrt(2.f - 2.f * u);
    return x * radius;
}
float pdf_tent(float x, float radius);

}  // namespace lpt
