// Arbitrary output variables of the first camera hit, at any resolution (the refiner wants them
// at latent resolution): world shading normal (facing the camera), distance along the camera ray (0 on a miss) and
// albedo. Averaged over `spp` filter samples per pixel with the renderer's random numbers.
#pragma once
#include "core/scene.h"
#include "core/scene_spectra.h"
#include <vector>

namespace lpt {

struct AovImages {
    int width = 0, height = 0;
    std::vector<float> normal;    ///< 3 per pixel, world space, turned toward the camera, averaged (not renormalised)
    std::vector<float> distance;  ///< 1 per pixel
    std::vector<float> albedo;    ///< 3 per pixel
};

AovImages render_aovs(const Scene& scene, const SceneSpectra<3>& spectra, int width, int height, int spp, uint64_t seed,
                      SamplerKind sampler = SamplerKind::Sobol);

/// Where emitters lie inside each pixel: the pixel split into cells × cells sub-cells, each the
/// fraction of its area whose camera ray first hits an emissive shape, from a regular grid of
/// rays_per_side² rays per sub-cell (deterministic: coverage is geometry, not light). The
/// refiner reads it because a pixel's average coverage says how much of it an emitter covers
/// but not where its edge runs, which the VAE's encoding of a sharp edge depends on
/// (docs/refiner.md "Emitter cells"). width × height × cells² values, sub-cells row-major.
std::vector<float> render_emitter_cells(const Scene& scene, int width, int height, int cells, int rays_per_side = 4);

/// What the camera's rays meet first on the film, from a regular grid of rays_per_side² rays per
/// pixel (geometry, deterministic). The film only, although a tent filter's samples land up to
/// half a pixel past its edge: a fit's target is encoded from a picture rendered at the VAE's
/// downsample times the latent resolution, whose samples reach 1/16 of a latent pixel past it.
struct CameraSights {
    std::vector<char> front_of;  ///< per shape: some ray meets the side its shading normal faces
    /// How many pixels' worth of rays meet the back of a shape whose BSDF does not scatter from
    /// below (black in RGB; the side by the shading normal, as the path tracer has it). A few
    /// rays can meet one where no surface turns its back: along a smooth-shaded silhouette the
    /// normal turns away from faces the camera sees, and a ray may slip between two triangles.
    float black_back_pixels = 0.f;
    bool nothing = false;  ///< some ray hits nothing
};
CameraSights camera_sights(const Scene& scene, const SceneSpectra<3>& spectra, int width, int height,
                           int rays_per_side = 8);

/// The fraction of each pixel whose camera ray first hits each shape of `shapes`, from a regular
/// grid of rays_per_side² rays per pixel (geometry, deterministic): width × height × shapes.size()
/// values, the shapes' in their order per pixel. A shape of -1 counts the rays that hit nothing.
std::vector<float> render_shape_coverage(const Scene& scene, int width, int height, const std::vector<int>& shapes,
                                         int rays_per_side = 8);

}  // namespace lpt
