// Emitters the training view never shows (a pendant lamp's bulb inside its shade): the fit saw
// the light they cast but not what they look like, and their L̃e seen directly decodes to noise
// (a rainbow disk where Living Room's raised bulb comes into view). Where an edited view sees
// one, its latent pixels take the VAE's encoding of the emitter's display colour instead,
// blended by how much of each pixel it covers (docs/edits.md "Emitters the training view does
// not show"). Emitters the training view shows keep their fitted look: scenes without unseen
// emitters render as before, byte for byte.
#pragma once
#include "pipeline/fit_folder.h"
#include <vector>

namespace lpt {
class Vae;
}

namespace lpt::pipeline {

class UnseenEmitters {
public:
    UnseenEmitters() = default;
    /// The area emitters of `fit`'s scene (as loaded: the training view) that no latent pixel of
    /// it sees, and each one's latent from the fit's VAE (opened only if there are any). None
    /// when the VAE is not here (frames are then latents only, nothing decodes them).
    explicit UnseenEmitters(const FitFolder& fit);
    bool empty() const { return m_shapes.empty(); }
    const std::vector<int>& shapes() const { return m_shapes; }
    /// Their coverage of the scene's current view at w × h (render_shape_coverage).
    std::vector<float> coverage(const Scene& scene, int w, int h) const;
    /// latent ← (1 − c) latent + c · the emitter's latent, per pixel and unseen emitter with
    /// coverage c; `latent` is tone-mapped (what the VAE reads), w × h × channels.
    void paint(const std::vector<float>& coverage, int w, int h, std::vector<float>& latent) const;

private:
    std::vector<int> m_shapes;                ///< the unseen emitters' shapes
    std::vector<std::vector<float>> m_looks;  ///< each one's latent (channels values)
};

/// The latent of a flat image of display colour `rgb`: the mean over the inner half of a 64²
/// latent encoding, away from the encoder's borders.
std::vector<float> flat_colour_latent(const Vae& vae, const float rgb[3]);

}  // namespace lpt::pipeline
