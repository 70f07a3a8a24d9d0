// Emitters the training view never shows (a pendant lamp's bulb inside its shade): the fit saw
// the light they cast but not what they look like, and their L̃e seen directly decodes to noise
// (a rainbow disk where Living Room's raised bulb comes into view). The environment is one too:
// camera rays that hit nothing see it (black in a scene without one), and a camera orbit past a
// closed room's walls shows what the training view never did (Lamp's b̃ decoded to brown stripes
// there). Edited frames render each in its look, the VAE's encoding of its display colour, for
// the camera rays that meet it (LatentTerms::looks; docs/edits.md "Emitters the training view
// does not show"). Emitters the training view shows keep their fitted look, and a frame that is
// the training view is rendered without looks.
#pragma once
#include "autodiff/tone_curve.h"
#include "integrators/path.h"
#include "latent/latent.h"
#include "pipeline/fit_folder.h"
#include <optional>
#include <string>
#include <vector>

namespace lpt {
class Vae;
}

namespace lpt::pipeline {

class UnseenEmitters {
public:
    UnseenEmitters() = default;
    /// The area emitters of `fit`'s scene whose emitting side no camera ray of the training view
    /// meets, the environment if every one meets a surface, black backs if too few meet one to
    /// have been fitted (less than a latent pixel's worth; camera_sights), and the latent of each
    /// (its colour in `fit`'s scene) from the fit's VAE (opened only if there are any). The
    /// training view is `training_view` when given (the scene as fitted, where `fit` was loaded
    /// with -D overrides that may change what the camera sees), else `fit`'s scene. None when the
    /// VAE is not here (frames are then latents only, nothing decodes them).
    explicit UnseenEmitters(const FitFolder& fit, const Scene* training_view = nullptr);
    /// No unseen area emitter (the environment aside).
    bool empty() const { return m_shapes.empty(); }
    /// The unseen area emitters' shapes.
    const std::vector<int>& shapes() const { return m_shapes; }
    bool environment_unseen() const { return m_environment.has_value(); }
    /// Black's latent, which the black backs of one-sided surfaces take where the training view
    /// shows too few to have fitted b̃ to them (b̃ was then fitted to the background; RGB shows
    /// them black, not in the environment's colour).
    const std::optional<std::vector<float>>& black() const { return m_black; }
    /// What gets a look, as text ("shape 3 the environment black backs"; empty: nothing): edited
    /// frames' keys record it, so that frames made when other rules decided what is unseen are
    /// rendered again (pipeline/edit.cpp).
    std::string key() const;
    /// Gives `terms` (of a scene with `shapes` shapes) the looks, as linear latents under `tone`
    /// (the renderer mixes a look into a pixel in proportion to its rays that meet it, before the
    /// tone curve, as it mixes everything else); with `on` false, takes them away.
    void show(LatentTerms<kLatentChannels>& terms, ToneCurve tone, size_t shapes, bool on) const;

private:
    std::vector<int> m_shapes;                        ///< the unseen emitters' shapes
    std::vector<std::vector<float>> m_looks;          ///< each one's latent (channels values)
    std::optional<std::vector<float>> m_environment;  ///< the environment's latent, when unseen
    std::optional<std::vector<float>> m_black;        ///< black's latent, when backs are unseen
};

/// The latent of a flat image of display colour `rgb`: the mean over the inner half of a 64²
/// latent encoding, away from the encoder's borders.
std::vector<float> flat_colour_latent(const Vae& vae, const float rgb[3]);

}  // namespace lpt::pipeline
