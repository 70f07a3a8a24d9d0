// Warps from [0,1)^2 to sampling domains, each paired with its pdf by a shared stem
// (sample_X / pdf_X). Equations: docs/sampling.md.
#pragma once
#include "core/geometry.h"

namespace lpt {

Vec2f sample_uniform_disk_concentric(const Vec2f& u);
Vec3f sample_cosine_hemisphere(const Vec2f& u);
float pdf_cosine_hemisphere(const Vec3f& w);
Vec3f sample_uniform_sphere(const Vec2f& u);
float pdf_uniform_sphere(const Vec3f& w);
/// Barycentrics (b1, b2) uniform over a triangle.
Vec2f sample_uniform_triangle(const Vec2f& u);
/// Tent filter of radius r on [-r, r]: triangle-shaped density.
float sample_tent(float u, float radius);
float pdf_tent(float x, float radius);

}  // namespace lpt
