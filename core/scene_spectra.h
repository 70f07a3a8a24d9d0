// SceneSpectra<N>: the channel-count-specific half of a scene: the BSDFs and the emitted radiance
// of each emitter, as N-channel spectra. The RGB renderer builds it with N = 3 from the scene
// description, one BSDF per material; the latent renderer fills N = 16 from learned parameters,
// one BSDF per shape (the paper's per-shape model), without touching the scene's materials.
#pragma once
#include "core/bsdf.h"
#include "core/scene.h"
#include <memory>
#include <vector>

namespace lpt {

template <int N>
struct SceneSpectra {
    std::vector<std::unique_ptr<BSDF<N>>> bsdfs;  ///< per material, or per shape (per_shape)
    std::vector<uint8_t> only_delta;              ///< per bsdfs entry: BSDF::is_delta(), cached (hot in NEE)
    std::vector<int> shape_bsdf;                  ///< per Scene::shapes entry: its index in bsdfs
    std::vector<Spectrum<N>, Eigen::aligned_allocator<Spectrum<N>>> radiance;  ///< per Scene::emitters entry

    const BSDF<N>& bsdf_of(const Scene&, int shape) const { return *bsdfs[shape_bsdf[shape]]; }
    BSDF<N>& bsdf_of(int shape) { return *bsdfs[shape_bsdf[shape]]; }
    bool is_delta(const Scene&, int shape) const { return only_delta[shape_bsdf[shape]] != 0; }
    /// From the scene's RGB descriptions (spectrum_from_rgb<N>), one BSDF per material.
    static SceneSpectra from_description(const Scene& scene);
    /// As from_description, but every shape gets its own BSDF built from its material, so two
    /// shapes that share a material in the scene file can take different values.
    static SceneSpectra per_shape(const Scene& scene);
};

}  // namespace lpt
