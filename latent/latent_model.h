// LatentModel: the learnable latent scene. For every shape it owns ParamStore slices
// ("<id>.Le" for emitters, "<id>.La"/"<id>.Lc" for non-delta shapes, "<id>.bsdf.<key>" for each
// BSDF coefficient) plus "background", and writes their values into the N = 16 spectra and
// latent terms the renderer reads. Its spectra hold one BSDF per shape, so two shapes that share a
// BSDF in the scene file still learn their own reflectance (the paper's per-shape model); the
// scene itself is only read.
// Parameterisations: docs/params.md.
#pragma once
#include "core/scene.h"
#include "core/scene_spectra.h"
#include "integrators/path.h"
#include "latent/latent.h"
#include "latent/param_store.h"
#include <string>
#include <vector>

namespace lpt {

/// Paper: signed values as pos − neg parts clipped to [0, hi], init U[0, 1] (reflectance parts
/// in [0, 1]). Code (public implementation): reflectance = sigmoid(raw), init raw U[−1, 1];
/// radiance-like vectors raw in [−6, 6], init U[−0.1, 0.1]. Roughness alpha is not a signed
/// vector: sigmoid in both, initialised at the scene file's value.
/// Paper / Code: the two signed parameterisations; Classic: the paper's baseline, every vector
/// non-negative (reflectances sigmoid in (0, 1), radiances clamped to [0, 1e4]) for a classic
/// render in [0, 1) that the logit tone curve maps to latent space. Gain: Code, but each
/// emitter's L̃e = e^g · u with u in [−6, 6] and one learnable log-gain g (starts at 0, so the
/// first render is Code's): a light that reaches the image only after bounces needs far more than
/// 6. docs/params.md.
enum class Parameterisation { Paper, Code, Classic, Gain };
Parameterisation parameterisation_from_string(const std::string& s);  ///< "paper" | "code" | "classic" | "gain"

class LatentModel {
public:
    /// Creates every slice and initialises it deterministically from `seed`. `scene` is read,
    /// never modified, and must outlive the model (edits of its shapes are seen by the model).
    LatentModel(const Scene& scene, Parameterisation p, uint64_t seed);

    struct ShapeSlots {
        int Le = -1, La = -1, Lc = -1;
        std::vector<std::pair<std::string, int>> bsdf;    ///< (coefficient key, slice)
        std::vector<std::pair<std::string, int>> scalar;  ///< (scalar key, 1-channel slice), e.g. alpha
    };

    /// Writes ParamStore values into spectra and terms (call after every optimiser step).
    void sync();
    /// Every light's L̃e (emitting shapes and the environment) times k in the spectra the renderer
    /// reads, the parameters untouched: the scene with all its lights k times as bright, which
    /// the next sync() undoes. Ĩe is linear in L̃e, so its render is k · Ĩe.
    void scale_emission(float k);

    const Scene& scene() const { return m_scene; }
    ParamStore& params() { return m_params; }
    const ParamStore& params() const { return m_params; }
    const SceneSpectra<kLatentChannels>& spectra() const { return m_spectra; }
    LatentTerms<kLatentChannels>& terms() { return m_terms; }
    const LatentTerms<kLatentChannels>& terms() const { return m_terms; }
    const ShapeSlots& slots(int shape) const { return m_slots[shape]; }
    int environment_slot() const { return m_env_slot; }  ///< Le of the constant emitter, or -1
    int background_slot() const { return m_background; }

private:
    const Scene& m_scene;
    ParamStore m_params;
    SceneSpectra<kLatentChannels> m_spectra;
    LatentTerms<kLatentChannels> m_terms;
    std::vector<ShapeSlots> m_slots;
    int m_env_slot = -1, m_background = -1;
};

}  // namespace lpt
