// The wavefront path tracer's stages for one tile, in the order the bounce loop runs them:
// intersect → resolve hits (escaped | emitter hit → shade queue) → sample lights (NEE → shadow
// queue) → sample BSDFs (+ Russian roulette → next ray queue) → trace shadow rays → swap ray
// queues. Internal to integrators/: path.cpp drives it over tiles. Equations: docs/transport.md
// (1)–(4), the latent terms (5)–(7). Random dimensions: core/sampler.h.
#pragma once
#include "core/bsdf.h"
#include "core/camera.h"
#include "core/light_sampler.h"
#include "integrators/latent_stage.h"
#include "integrators/path.h"
#include "integrators/wavefront_state.h"
#include <optional>
#include <vector>

namespace lpt {

/// One worker's reusable arrays for a wavefront of paths.
template <int N>
struct TileWorkspace {
    RayArrays rays[2];
    ShadowQueue<N> shadow;
    ShadeQueue shade;
    AlignedVector<float> u_lobe, u_dir[2], cosine[3];  ///< per shade entry: BSDF randoms, warped direction
    AlignedVector<float> film[2];                      ///< per camera ray: pixel column and row
    LightBatch lights;                                 ///< per shade entry: the NEE light sample
    PathState<N> paths;
    std::vector<uint32_t> queue[2];
};

/// Traces the paths of one tile's samples; const and shared by every worker.
template <int N>
class PathTracer {
public:
    PathTracer(const Scene& scene, const SceneSpectra<N>& spectra, const RenderOptions& opt, const Camera& camera,
               const LatentTerms<N>* terms, PathObserver<N>* observer);

    /// Traces samples [s0, s0 + count) of every pixel in [x0,x1)×[y0,y1) and adds them to film.
    /// films[1], films[2] (Ĩa, Ĩc) are written only for latent terms.
    void trace_tile(TileWorkspace<N>& ws, Film<N>* const films[3], int tile, int x0, int y0, int x1, int y1, int s0,
                    int count, RenderStats& st) const;

private:
    void generate_camera_rays(TileWorkspace<N>& ws, int x0, int y0, int x1, int s0, int count, size_t n,
                              RenderStats& st) const;

    /// Radiance of emitter e arriving along -w (w points from the scene toward the emitter):
    /// SceneSpectra's spectrum, and for an environment map its direction dependence: the RGB
    /// texel itself for N = 3, the texel's relative luminance times the (learned) spectrum for
    /// latent N. `factor` is that scalar (1 otherwise), folded into the observer's weights so path
    /// replay sees radiance[e] · factor.
    Spectrum<N> emitted(int e, const Vec3f& w, float* factor) const;

    /// docs/transport.md (3): weight of an emitter reached by BSDF sampling.
    float hit_weight(const PathState<N>& p, uint32_t slot, float light_pdf) const;

    /// Stage 1: escaped rays and emitter hits collect emission (docs/transport.md (3)); vertices
    /// allowed another segment go to the shade queue.
    void resolve_hits(TileWorkspace<N>& ws, int cur, int depth) const;

    /// Stage 2: next-event estimation (docs/transport.md (2)) for every non-delta vertex; at the
    /// latent first vertex the same light sample gates Ĩc (docs/transport.md (7)).
    void sample_lights(TileWorkspace<N>& ws, int depth) const;

    /// The stage's random numbers in `dimension` (and the next, with u1) for every shade entry.
    void draw(const ShadeQueue& sq, uint32_t dimension, float* u0, float* u1 = nullptr) const;

    /// Every shade entry's light sample at once (core/light_sampler.h): per vertex it is a long
    /// dependent chain of square roots and divisions.
    void draw_light_samples(TileWorkspace<N>& ws, int depth) const;

    /// A first vertex whose light sample is known to be unlit without a ray (no light, or an
    /// attached shadow): Ĩc's gate with V = 0.
    void gate_unlit(PathState<N>& p, const ShadeQueue& sq, size_t k, const Spectrum<N>& occl) const;

    /// The shadow ray from vertex p (normal ng) to the light sample. It aims from the offset
    /// origin at the light point itself: reusing ls.wi from the un-offset point makes the ray
    /// cross the light's plane before tmax and hit the light (up to half the NEE energy lost
    /// under large, close lights).
    void push_shadow_ray(RayArrays& rays, const Vec3f& p, const Vec3f& ng, const LightSample& ls) const;

    /// Stage 3: BSDF sampling (docs/transport.md (1)) and Russian roulette (4) → next rays.
    void sample_bsdfs(TileWorkspace<N>& ws, int cur, int depth) const;

    /// Stage 4: shadow rays decide NEE contributions and, for latent first vertices, Ĩc's gate
    /// (those known unlit without a ray were gated in stage 2 by gate_unlit).
    void trace_shadow_rays(TileWorkspace<N>& ws, RenderStats& st) const;

    const Scene& m_scene;
    const SceneSpectra<N>& m_spectra;
    const RenderOptions& m_opt;
    const Camera& m_camera;
    PathObserver<N>* m_obs;                  ///< null unless an adjoint is replaying
    std::optional<LatentStage<N>> m_latent;  ///< Ĩa, Ĩc: absent for plain (RGB) rendering
    const bool m_emission;                   ///< Ĩe on
    /// Latent renders keep zero-valued NEE samples and zero-throughput paths: their derivatives
    /// need not be zero. Decided by what is rendered, never by whether an observer listens.
    const bool m_keep_zero;
    std::vector<Lambertian> m_lambertian;  ///< per shape: sampled from the batch-warped direction
    std::vector<bool> m_scatters_below;    ///< per shape: its BSDF scatters light arriving from behind
};

extern template class PathTracer<3>;
extern template class PathTracer<16>;

}  // namespace lpt
