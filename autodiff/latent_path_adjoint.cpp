// The adjoint of the wavefront tracer (integrators/path_tracer.cpp): the tracer runs again with
// the primal's random numbers and a PathRecorder attached; each finished wavefront's records are
// swept backwards at once (detail::backward_block) and forgotten, so memory stays one wavefront
// however many samples there are. docs/path-replay.md (1)–(6).
#include "autodiff/latent_path_adjoint.h"
#include "autodiff/path_record.h"
#include <stdexcept>

namespace lpt {

namespace {

class Adjoint final : public detail::PathRecorder {
public:
    Adjoint(const LatentModel& model, const RenderOptions& opt, const std::vector<float>& d_image, int n_tiles)
        : PathRecorder(n_tiles),
          m_model(model),
          m_sampler{opt.seed, opt.sampler},
          m_d_image(d_image),
          m_inv_spp(1.f / float(opt.spp)),
          m_tile_grads(n_tiles) {}

    /// Sums the per-tile buffers in tile order into `out` (deterministic).
    void reduce(std::vector<float>& out) const {
        for (const auto& g : m_tile_grads)
            for (size_t i = 0; i < g.size(); ++i) out[i] += g[i];
    }

protected:
    void complete(int tile, PathBlock& block) override {
        // One task owns a tile: its buffer is never shared between threads.
        std::vector<float>& g = m_tile_grads[tile];
        if (g.empty()) g.assign(m_model.params().values().size(), 0.f);
        detail::backward_block(m_model, m_sampler, block, m_d_image.data(), m_inv_spp, g.data());
    }

private:
    const LatentModel& m_model;
    SamplerId m_sampler;
    const std::vector<float>& m_d_image;
    float m_inv_spp;
    std::vector<std::vector<float>> m_tile_grads;
};

}  // namespace

std::vector<float> backward_latent(LatentModel& model, const RenderOptions& opt, const std::vector<float>& d_image,
                                   RenderStats* stats) {
    const Scene& scene = model.scene();
    const int w = opt.width > 0 ? opt.width : scene.camera.width, h = opt.height > 0 ? opt.height : scene.camera.height;
    if (d_image.size() != size_t(w) * h * kLatentChannels)
        throw std::invalid_argument("backward_latent: d_image has " + std::to_string(d_image.size()) +
                                    " floats, expected " + std::to_string(size_t(w) * h * kLatentChannels));
    Adjoint adjoint(model, opt, d_image, render_tile_count(w, h));
    TermFilms<kLatentChannels> films =
        render_latent_terms<kLatentChannels>(scene, model.spectra(), model.terms(), opt, stats, &adjoint);
    adjoint.reduce(model.params().grad_values());
    return films.sum();
}

}  // namespace lpt
