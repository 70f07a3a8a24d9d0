// RenderOptions from a scene's integrator settings.
#include "integrators/path.h"

namespace lpt {

RenderOptions RenderOptions::from_scene(const Scene& scene) {
    RenderOptions o;
    o.spp = scene.integrator.spp;
    o.max_depth = scene.integrator.max_depth;
    o.rr_depth = scene.integrator.rr_depth;
    o.sampler = scene.integrator.sampler;
    return o;
}

RenderOptions RenderOptions::from_scene(const Scene& scene, int width, int height, int spp, uint64_t seed) {
    RenderOptions o = from_scene(scene);
    o.width = width;
    o.height = height;
    o.spp = spp;
    o.seed = seed;
    return o;
}

}  // namespace lpt
