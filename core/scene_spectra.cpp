#include "core/scene_spectra.h"

namespace lpt {

namespace {

template <int N>
void add_bsdf(SceneSpectra<N>& s, const Props& description) {
    s.bsdfs.push_back(make_bsdf<N>(description));
    s.only_delta.push_back(s.bsdfs.back()->is_delta());
}

template <int N>
void add_radiance(SceneSpectra<N>& s, const Scene& scene) {
    for (const Emitter& e : scene.emitters) s.radiance.push_back(spectrum_from_rgb<N>(e.radiance_rgb));
}

}  // namespace

template <int N>
SceneSpectra<N> SceneSpectra<N>::from_description(const Scene& scene) {
    SceneSpectra<N> s;
    for (const Props& p : scene.materials) add_bsdf(s, p);
    for (const Shape& shape : scene.shapes) s.shape_bsdf.push_back(shape.material);
    add_radiance(s, scene);
    return s;
}

template <int N>
SceneSpectra<N> SceneSpectra<N>::per_shape(const Scene& scene) {
    SceneSpectra<N> s;
    for (const Shape& shape : scene.shapes) {
        s.shape_bsdf.push_back(int(s.bsdfs.size()));
        add_bsdf(s, scene.materials[shape.material]);
    }
    add_radiance(s, scene);
    return s;
}

template struct SceneSpectra<3>;
template struct SceneSpectra<16>;

}  // namespace lpt
