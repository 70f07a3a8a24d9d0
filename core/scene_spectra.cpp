#include "core/scene_spectra.h"

namespace lpt {

template <int N>
SceneSpectra<N> SceneSpectra<N>::from_description(const Scene& scene) {
    SceneSpectra<N> s;
    for (const Props& p : scene.materials) {
        s.bsdfs.push_back(make_bsdf<N>(p));
        s.only_delta.push_back(s.bsdfs.back()->is_delta());
    }
    for (const Emitter& e : scene.emitters) s.radiance.push_back(spectrum_from_rgb<N>(e.radiance_rgb));
    return s;
}

template struct SceneSpectra<3>;
template struct SceneSpectra<16>;

}  // namespace lpt
