// Wavefront unidirectional path tracer, primal only, templated on the channel count N.
// Next-event estimation and BSDF sampling combined by the power heuristic (docs/transport.md).
// Output is a pure function of (scene, spectra, options): per-pixel deterministic random numbers
// and per-tile ownership of pixels make it independent of the thread count.
#pragma once
#include "core/film.h"
#include "core/sampler.h"
#include "core/scene.h"
#include "core/scene_spectra.h"
#include "integrators/path_events.h"
#include "integrators/path_observer.h"
#include <cstdint>
#include <functional>

namespace lpt {

/// Which estimator collects light: both combined (MIS), or one alone (for tests/debugging).
enum class LightStrategy { Mis, Nee, Bsdf };

struct RenderOptions {
    uint64_t seed = 0;
    int spp = 16;
    int width = 0, height = 0;  ///< 0 = the camera's resolution
    int max_depth = 8;          ///< Mitsuba semantics: 1 = emitters seen directly; -1 = unbounded
    int rr_depth = 5;
    LightStrategy strategy = LightStrategy::Mis;
    SamplerKind sampler = SamplerKind::Sobol;  ///< docs/sampling.md
    /// Called now and then with (fraction done, rays traced so far); from a worker thread.
    std::function<void(double, uint64_t)> progress;
    /// The scene's settings, its sampler included (load_scene's `sampler` replaces the file's).
    static RenderOptions from_scene(const Scene& scene);
    /// The same for an image of width × height (0: the camera's) at `spp` samples with `seed`.
    static RenderOptions from_scene(const Scene& scene, int width, int height, int spp, uint64_t seed);
};

struct RenderStats {
    uint64_t camera_rays = 0, extension_rays = 0, shadow_rays = 0;
    double seconds = 0.0;
    uint64_t rays() const { return camera_rays + extension_rays + shadow_rays; }
};

template <int N>
Film<N> render_path(const Scene& scene, const SceneSpectra<N>& spectra, const RenderOptions& options,
                    RenderStats* stats = nullptr);

/// The latent renderer's terms beyond light transport (docs/transport.md, latent section).
template <int N>
struct LatentTerms {
    std::vector<Spectrum<N>, Eigen::aligned_allocator<Spectrum<N>>> La, Lc;  ///< per shape
    Spectrum<N> background = Spectrum<N>::Zero();  ///< camera paths escaping along delta bounces
    /// Edits only (pipeline/unseen_emitters.h): what a camera ray scores, into Ĩa and nothing
    /// else, where it first meets what the training view never showed: looks[look_of_shape[s]]
    /// on the emitting side of shape s (where that index is ≥ 0), looks[look_of_nothing] where it
    /// hits nothing, looks[look_of_black] where it meets the black back of a one-sided surface.
    /// Empty and -1: none. Never in a render with an observer (a fit's adjoint does not know them).
    std::vector<int> look_of_shape;
    int look_of_nothing = -1, look_of_black = -1;
    std::vector<Spectrum<N>, Eigen::aligned_allocator<Spectrum<N>>> looks;
    OcclusionGate gate = OcclusionGate::Shadowed;
    bool emission = true, ambient = true, occlusion = true;  ///< which of Ĩe, Ĩa, Ĩc to render
};

template <int N>
struct TermFilms {
    Film<N> e, a, c;                 ///< Ĩe (light transport), Ĩa (+ background), Ĩc
    std::vector<float> sum() const;  ///< developed Ĩe + Ĩa + Ĩc, N floats per pixel
};

/// One pass that renders the three latent terms with the same paths (common random numbers).
/// With an observer, every path also reports its events (the adjoint's replay); the observer must
/// be safe to call from several threads for different tiles. An observer never changes what is
/// rendered: latent renders always keep zero-valued NEE samples and zero-throughput bounces,
/// since their derivatives need not be zero (RGB renders drop them).
template <int N>
TermFilms<N> render_latent_terms(const Scene& scene, const SceneSpectra<N>& spectra, const LatentTerms<N>& terms,
                                 const RenderOptions& options, RenderStats* stats = nullptr,
                                 PathObserver<N>* observer = nullptr);

/// Image tiles of a render at this resolution (observers index per-tile buffers by tile).
int render_tile_count(int width, int height);

/// Power heuristic (beta = 2) of sampling technique a against b (both as solid-angle pdfs).
inline float mis_power(float pdf_a, float pdf_b) {
    float a2 = pdf_a * pdf_a, b2 = pdf_b * pdf_b;
    return a2 > 0.f ? a2 / (a2 + b2) : 0.f;
}

}  // namespace lpt
