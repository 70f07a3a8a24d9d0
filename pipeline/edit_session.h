// One edited view of a fitted latent scene in memory: what `render --edit` computes for frame i
// (the latent at seed + i, and with the fit's refiner the AOVs and the refined latent), for
// callers that want arrays rather than files (the Python module, tests).
#pragma once
#include "core/mesh.h"
#include "core/scene_edit.h"
#include "pipeline/fit_folder.h"
#include "refiner/refiner.h"
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace lpt::pipeline {

struct FrameLatents {
    int width = 0, height = 0;
    std::vector<float> latent;   ///< tone-mapped, width x height x 16
    std::vector<float> refined;  ///< empty without a refiner
    RefinerInput view;           ///< the refiner's input (latent + AOVs); empty without a refiner
};

/// Frame `i` of the already edited scene of `fit`, rendered at spp with seed (render --edit uses
/// seed + i), refined when `refiner` is given.
FrameLatents edited_frame(const FitFolder& fit, const Refiner* refiner, int width, int height, int spp, uint64_t seed);

class EditSession {
public:
    /// Loads the fit folder (defines override its -D values), its refiner when it has one, and
    /// the edit sequence; throws naming the file on bad input.
    EditSession(const std::string& fitdir, const std::string& edits,
                const std::map<std::string, std::string>& defines = {});
    int frames() const { return m_edits.frames; }
    bool has_refiner() const { return m_refiner != nullptr; }
    int latent_width() const { return m_fit.latent_width; }
    int latent_height() const { return m_fit.latent_height; }
    /// Frame i as `render --edit --seed seed` renders it (0 = the fit's latent resolution).
    FrameLatents frame(int i, int spp = 64, uint64_t seed = 0, int width = 0, int height = 0);

private:
    FitFolder m_fit;
    EditSequence m_edits;
    std::unique_ptr<Refiner> m_refiner;
    std::vector<TriangleMesh> m_original;
    Camera m_camera;
};

}  // namespace lpt::pipeline
