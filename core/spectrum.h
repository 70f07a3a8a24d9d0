// Spectrum<N>: N signed channels carried along a path. N = 3 for the RGB path tracer,
// N = 16 for latent transport (docs/transport.md). Values are never clamped here: latent
// reflectances and radiances are signed, so any clamping belongs to whoever owns the meaning.
#pragma once
#include <Eigen/Core>

namespace lpt {

template <int N>
using Spectrum = Eigen::Array<float, N, 1>;

using Color3 = Spectrum<3>;

/// RGB description value (from a scene file) → N channels. N = 3 copies; other N broadcast the
/// luminance, a neutral start that the latent parameter store overrides.
template <int N>
inline Spectrum<N> spectrum_from_rgb(const Eigen::Array3f& rgb) {
    if constexpr (N == 3) {
        return rgb;
    } else {
        float y = 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2];
        return Spectrum<N>::Constant(y);
    }
}

inline float luminance(const Color3& c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

}  // namespace lpt
