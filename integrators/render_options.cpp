// RenderOptions from a scene, and the command line's process-wide sampler override.
#include "integrators/path.h"

namespace lpt {

namespace {
bool g_sampler_overridden = false;
SamplerKind g_sampler_override = SamplerKind::Sobol;
}  // namespace

void set_sampler_override(SamplerKind kind) {
    g_sampler_overridden = true;
    g_sampler_override = kind;
}

RenderOptions RenderOptions::from_scene(const Scene& scene) {
    RenderOptions o;
    o.spp = scene.integrator.spp;
    o.max_depth = scene.integrator.max_depth;
    o.rr_depth = scene.integrator.rr_depth;
    o.sampler = g_sampler_overridden ? g_sampler_override : scene.integrator.sampler;
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
