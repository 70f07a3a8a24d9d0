// One edited view of a fitted latent scene in memory: what `render --edit` computes for frame i
// (the latent at seed + i, and with the fit's refiner the AOVs and the refined latent), for
// callers that want arrays rather than files (the Python module, tests).
#pragma once
#include "core/mesh.h"
#include "core/scene_edit.h"
#include "pipeline/fit_folder.h"
#include "pipeline/unseen_emitters.h"
#include "refiner/refiner.h"
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace lpt::pipeline {

struct FrameLatents {
    int width = 0, height = 0;
    std::vector<float> latent;   ///< tone-mapped, width x height x 16
    std::vector<float> refined;  ///< empty without a refiner
    RefinerInput view;           ///< the refiner's input (latent + AOVs); empty without a refiner
};

class EditSession {
public:
    /// Loads the fit folder (defines override its -D values, sampler its sampler), its refiner and
    /// emitter refiner when it has them (pipeline/emitter_refiner.h), and the edit sequence;
    /// throws naming the file on bad input.
    EditSession(const std::string& fitdir, const std::string& edits,
                const std::map<std::string, std::string>& defines = {},
                std::optional<SamplerKind> sampler = std::nullopt);
    int frames() const { return m_edits.frames; }
    bool has_refiner() const { return m_refiner != nullptr; }
    int latent_width() const { return m_fit.latent_width; }
    int latent_height() const { return m_fit.latent_height; }
    /// The edit parameter t in [0, 1) of frame i.
    float time(int i) const { return float(i) / float(m_edits.frames); }
    /// Frame i as `render --edit --seed seed` renders it (0 = the fit's latent resolution): the
    /// scene is edited to time(i) and rendered with seed + i, so a frame depends on i alone.
    /// Calls from several threads (Python's, which frame() lets run) take turns: each edits the
    /// one scene the session holds.
    FrameLatents frame(int i, int spp = 64, uint64_t seed = 0, int width = 0, int height = 0);
    /// Whether frame i is the scene as fitted (core/scene_edit.h is_unedited).
    bool unedited(int i) const { return is_unedited(m_edits, time(i)); }
    /// The fit, its scene as the last frame() left it (for path-traced references of that frame).
    const FitFolder& fit() const { return m_fit; }
    /// Emitters (the environment among them) the training view does not show, which edited
    /// frames render in looks from the VAE (pipeline/unseen_emitters.h).
    const UnseenEmitters& unseen_emitters() const { return m_unseen; }

private:
    FitFolder m_fit;
    EditSequence m_edits;
    std::unique_ptr<Refiner> m_refiner;
    std::unique_ptr<Refiner> m_emitter_refiner;  ///< refiner_emitters.pt, when the fit folder has one
    std::vector<float> m_training_coverage;      ///< with it: emitter_coverage of the training view
    UnseenEmitters m_unseen;
    std::vector<TriangleMesh> m_original;
    Camera m_camera;
    /// -D overrides were given: no frame is then the training view, and what it showed is
    /// measured on the scene as fitted.
    bool m_overridden = false;
    std::mutex m_frame_mutex;  ///< frame() edits m_fit's scene and terms in place
};

}  // namespace lpt::pipeline
