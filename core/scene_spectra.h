// SceneSpectra<N>: the channel-count-specific half of a scene: one BSDF per material and the
// emitted radiance of each emitter, as N-channel spectra. The RGB renderer builds it with N = 3
// from the scene description; the latent renderer fills N = 16 from learned parameters.
#pragma once
#include "core/bsdf.h"
#include "core/scene.h"
#include <memory>
#include <vector>

namespace lpt {

template <int N>
struct SceneSpectra {
    std::vector<std::unique_ptr<BSDF<N>>> bsdfs;  ///< per Scene::materials entry
    std::vector<uint8_t> only_delta;              ///< per material: BSDF::is_delta(), cached (hot in NEE)
    std::vector<Spectrum<N>, Eigen::aligned_allocator<Spectrum<N>>> radiance;  ///< per Scene::emitters entry

    const BSDF<N>& bsdf_of(const Scene& scene, int shape) const { return *bsdfs[scene.shapes[shape].material]; }
    bool is_delta(const Scene& scene, int shape) const { return only_delta[scene.shapes[shape].material] != 0; }
    /// From the scene's RGB descriptions (spectrum_from_rgb<N>).
    static SceneSpectra from_description(const Scene& scene);
};

}  // namespace lpt
