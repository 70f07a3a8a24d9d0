// Perspective pinhole camera (Mitsuba conventions): camera space looks down +z, +y up, +x to
// the image's left; film position (0,0) is the top-left corner of the top-left pixel.
// Pixel filters are importance sampled (filter importance sampling): each sample lands in one
// pixel with weight 1, which keeps accumulation per pixel and deterministic.
#pragma once
#include "core/geometry.h"
#include "core/transform.h"
#include <string>

namespace lpt {

struct PixelFilter {
    enum class Type { Box, Tent } type = Type::Box;
    float radius = 0.5f;  ///< half-width in pixels (box default 0.5, tent default 1)
    /// Offset from the pixel centre, distributed as the filter.
    Vec2f sample(const Vec2f& u) const;
};

enum class FovAxis { X, Y, Smaller, Larger };

class Camera {
public:
    Transform world_from_camera;
    float fov = 45.f;  ///< degrees, along fov_axis
    FovAxis fov_axis = FovAxis::X;
    int width = 256, height = 256;
    float near_clip = 1e-2f, far_clip = 1e4f;
    PixelFilter filter;

    /// Ray through continuous film position (pixels). Direction is unit length; tmin/tmax are the
    /// clip distances along it.
    Ray generate_ray(const Vec2f& film_pos) const { return generate_ray(film_pos, tan_half_fov()); }
    /// Same, with tan_half_fov() computed once by the caller (it costs a tan per ray otherwise).
    Ray generate_ray(const Vec2f& film_pos, const Vec2f& tan_half) const;
    /// Camera rays for n samples at once, the floats of filter.sample + generate_ray one by one:
    /// pixel (px, py) + 0.5 + the filter offset from (u0, u1), written into Embree-layout arrays
    /// (origin, direction, tnear, tfar). Evaluated 4-8 wide (tests/integrators/test_lights_camera.cpp).
    struct RayOut {
        float *ox, *oy, *oz, *dx, *dy, *dz, *tnear, *tfar;
    };
    void generate_rays(size_t n, const float* px, const float* py, const float* u0, const float* u1,
                       const Vec2f& tan_half, const RayOut& out) const;
    /// Same camera at another resolution (fov semantics kept, e.g. latent res = image / 8).
    Camera with_resolution(int w, int h) const;
    /// Camera-space tangents of the half field of view in x and y.
    Vec2f tan_half_fov() const;
};

}  // namespace lpt
