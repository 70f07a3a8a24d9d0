#include "pipeline/edit_session.h"
#include "pipeline/emitter_refiner.h"
#include "pipeline/refiner_io.h"
#include <filesystem>
#include <stdexcept>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

/// The already edited scene of `fit` at spp with seed, refined when `refiner` is given, and by
/// `emitters` (when given) where emitters are seen otherwise than `training_coverage` says.
FrameLatents edited_frame(const FitFolder& fit, const Refiner* refiner, const Refiner* emitters,
                          const std::vector<float>& training_coverage, int width, int height, int spp, uint64_t seed) {
    FrameLatents f;
    f.width = width;
    f.height = height;
    if (!refiner) {
        f.latent = render_fit_latent(fit, width, height, spp, seed);
        return f;
    }
    // Same spp and seed as the fit's latent: an identity edit reproduces its refined latent.
    f.view = fit_refiner_view(fit, refiner->config(), width, height, spp, seed);
    f.latent = f.view.latent;
    f.refined = refine_with_emitters(*refiner, emitters, *fit.scene, f.view, training_coverage);
    return f;
}

}  // namespace

EditSession::EditSession(const std::string& fitdir, const std::string& edits,
                         const std::map<std::string, std::string>& defines, std::optional<SamplerKind> sampler)
    : m_fit(load_fit_folder(fitdir, defines, sampler)),
      m_edits(load_edits(edits, *m_fit.scene)),
      m_camera(m_fit.scene->camera),
      m_overridden(!defines.empty()) {
    // What the training view showed: the scene as fitted, not as the overrides leave it.
    std::unique_ptr<Scene> fitted;
    if (m_overridden) fitted = std::make_unique<Scene>(load_fitted_scene(m_fit));
    const Scene& training_view = fitted ? *fitted : *m_fit.scene;
    const fs::path pt = fs::path(fitdir) / "refiner.pt";
    if (fs::exists(pt)) m_refiner = Refiner::load(pt.string());
    const fs::path emitters = fs::path(fitdir) / kEmitterRefinerFile;
    if (fs::exists(emitters)) {
        if (!m_refiner)
            throw std::runtime_error(emitters.string() +
                                     ": an emitter refiner without refiner.pt beside it; train the "
                                     "main refiner (latentpt refine) or remove the file");
        m_emitter_refiner = Refiner::load(emitters.string());
        check_emitter_refiner_inputs(m_refiner->config(), m_emitter_refiner->config(), emitters.string());
        m_training_coverage = emitter_coverage(training_view, m_fit.latent_width, m_fit.latent_height);
    }
    for (const Shape& s : m_fit.scene->shapes) m_original.push_back(s.mesh);
    m_unseen = UnseenEmitters(m_fit, fitted.get());
}

FrameLatents EditSession::frame(int i, int spp, uint64_t seed, int width, int height) {
    if (i < 0 || i >= m_edits.frames)
        throw std::invalid_argument("frame " + std::to_string(i) +
                                    " is not within the sequence's 0:" + std::to_string(m_edits.frames - 1));
    if (spp < 1) throw std::invalid_argument("frame spp must be > 0, got " + std::to_string(spp));
    if (width < 0 || height < 0)
        throw std::invalid_argument("frame resolution must not be negative, got " + std::to_string(width) + "x" +
                                    std::to_string(height));
    const std::lock_guard<std::mutex> one_frame_at_a_time(m_frame_mutex);
    apply_edits(m_edits, time(i), m_original, m_camera, *m_fit.scene);
    m_unseen.show(m_fit.model->terms(), m_fit.tone, m_fit.scene->shapes.size(), m_overridden || !unedited(i));
    return edited_frame(m_fit, m_refiner.get(), m_emitter_refiner.get(), m_training_coverage,
                        width > 0 ? width : m_fit.latent_width, height > 0 ? height : m_fit.latent_height, spp,
                        seed + uint64_t(i));
}

}  // namespace lpt::pipeline
