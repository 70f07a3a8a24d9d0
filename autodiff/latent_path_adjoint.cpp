// The adjoint of integrators/path.cpp as a PathObserver: while the tracer replays a path it
// records each vertex's local contributions (without the throughput in front of them); at the
// end of a wavefront each path is swept backwards, carrying R, the radiance its suffix sends
// toward the current vertex, so that ∂/∂w_k of the whole path is β_k ∘ ∂w_k/∂c ∘ R without
// dividing by anything. docs/path-replay.md (1)–(5).
#include "autodiff/latent_path_adjoint.h"
#include <tbb/enumerable_thread_specific.h>
#include <stdexcept>

namespace lpt {

namespace {

using L = Latent;
/// Most colour coefficients of one BSDF: a textured roughplastic has diffuse .scale, .offset and
/// specular_reflectance. Checked when the adjoint is built: never silently truncated.
constexpr int kMaxKeys = 3;

struct Event {
    enum Type : uint8_t { Emission, Ambient, Light, Bounce } type = Emission;
    int shape = -1, emitter = -1;
    bool nee = false, first = false, visible = false;
    float scalar = 0.f;  ///< Emission: MIS weight; Light: w / pdf; Bounce: RR probability q
    L beta = L::Zero();  ///< throughput in front of this vertex
    L local = L::Zero(); ///< Bounce: weight / q; Light: ∂value/∂L̃e coefficient f · w / pdf
    L grad[kMaxKeys] = {L::Zero(), L::Zero(), L::Zero()};  ///< Light: ∂f/∂c_k · w/pdf; Bounce: ∂weight/∂c_k / q
    L sgrad = L::Zero();  ///< the same for the BSDF's scalar parameter (roughness), if any
};

struct PathEvents {
    std::vector<Event> events;
};

class Adjoint final : public PathObserver<kLatentChannels> {
public:
    Adjoint(LatentModel& model, const RenderOptions& opt, const std::vector<float>& d_image, int width, int n_tiles)
        : m_model(model), m_d_image(d_image), m_inv_spp(1.f / float(opt.spp)), m_tile_grads(n_tiles) {
        (void)width;
        for (size_t i = 0; i < model.scene().shapes.size(); ++i)
            if (model.slots(int(i)).bsdf.size() > size_t(kMaxKeys))
                throw std::logic_error("path replay: shape '" + model.scene().shapes[i].id + "' has more BSDF coefficients than kMaxKeys");
    }

    void begin(int tile, size_t n) override {
        // One lookup per wavefront: every hook until end() runs on this thread (path_observer.h).
        t_current = &m_scratch.local();
        Scratch& s = *t_current;
        s.tile = tile;
        if (s.paths.size() < n) s.paths.resize(n);
        for (size_t i = 0; i < n; ++i) s.paths[i].events.clear();
        if (m_tile_grads[tile].empty()) m_tile_grads[tile].assign(m_model.params().grad_values().size(), 0.f);
    }
    void emission(uint32_t slot, int emitter, const L& beta, float mis) override {
        Event e;
        e.type = Event::Emission;
        e.emitter = emitter;
        e.beta = beta;
        e.scalar = mis;
        push(slot, e);
    }
    void ambient(uint32_t slot, int shape, const L& beta) override {
        Event e;
        e.type = Event::Ambient;
        e.shape = shape;
        e.beta = beta;
        push(slot, e);
    }
    void light_sample(uint32_t slot, int shadow_id, int shape, int emitter, const L& beta, float w_over_pdf, const BSDFContext& ctx,
                      const Vec3f& wi, const Vec3f& wo, const L& f, bool nee, bool first) override {
        Event e;
        e.type = Event::Light;
        e.shape = shape;
        e.emitter = emitter;
        e.beta = beta;
        e.nee = nee;
        e.first = first;
        e.scalar = w_over_pdf;
        e.visible = false;
        if (nee) {
            const BSDF<kLatentChannels>& bsdf = m_model.spectra().bsdf_of(m_model.scene(), shape);
            e.local = f * w_over_pdf;
            const auto& keys = m_model.slots(shape).bsdf;
            for (size_t k = 0; k < keys.size() && k < kMaxKeys; ++k) e.grad[k] = bsdf.eval_grad(ctx, wi, wo, int(k)) * w_over_pdf;
            if (!m_model.slots(shape).scalar.empty()) e.sgrad = bsdf.eval_grad_scalar(ctx, wi, wo, 0) * w_over_pdf;
        }
        Scratch& s = *t_current;
        if (shadow_id >= 0) {
            if (s.pending.size() <= size_t(shadow_id)) s.pending.resize(shadow_id + 1);
            s.pending[shadow_id] = {slot, s.paths[slot].events.size()};
        }
        push(slot, e);
    }
    void shadow(int shadow_id, bool blocked) override {
        Scratch& s = *t_current;
        auto [slot, idx] = s.pending[shadow_id];
        s.paths[slot].events[idx].visible = !blocked;
    }
    void bounce(uint32_t slot, int shape, const L& beta, const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<kLatentChannels>& bs,
                float q) override {
        Event e;
        e.type = Event::Bounce;
        e.shape = shape;
        e.beta = beta;
        e.scalar = q;
        e.local = bs.weight / q;
        const BSDF<kLatentChannels>& bsdf = m_model.spectra().bsdf_of(m_model.scene(), shape);
        const auto& keys = m_model.slots(shape).bsdf;
        for (size_t k = 0; k < keys.size() && k < kMaxKeys; ++k) e.grad[k] = bsdf.weight_grad(ctx, wi, bs, int(k)) / q;
        if (!m_model.slots(shape).scalar.empty() && !(bs.lobe & kDelta)) e.sgrad = bsdf.weight_grad_scalar(ctx, wi, bs, 0) / q;
        push(slot, e);
    }

    /// docs/path-replay.md (2)–(5): reverse sweep per path.
    void end(const uint32_t* pixel, size_t n) override {
        Scratch& s = *t_current;
        std::vector<float>& g = m_tile_grads[s.tile];
        const ParamStore& ps = m_model.params();
        const auto& terms = m_model.terms();
        const bool gate_shadowed = terms.gate == OcclusionGate::Shadowed;
        for (size_t slot = 0; slot < n; ++slot) {
            const auto& ev = s.paths[slot].events;
            if (ev.empty()) continue;
            const L d = Eigen::Map<const L>(m_d_image.data() + size_t(pixel[slot]) * kLatentChannels) * m_inv_spp;
            auto add = [&](int slice, const L& v) {
                if (slice < 0) return;
                Eigen::Map<L>(g.data() + ps.slice(slice).value_offset) += v;
            };
            // A scalar parameter (roughness) scales every channel: its derivative sums them.
            auto add_scalar = [&](int shape, const L& v) {
                const auto& sc = m_model.slots(shape).scalar;
                if (!sc.empty()) g[ps.slice(sc[0].second).value_offset] += v.sum();
            };
            L R = L::Zero();
            for (size_t i = ev.size(); i-- > 0;) {
                const Event& e = ev[i];
                switch (e.type) {
                    case Event::Emission: {
                        const L& le = m_model.spectra().radiance[e.emitter];
                        R += e.scalar * le;
                        add(emitter_slice(e.emitter), d * e.beta * e.scalar);
                        break;
                    }
                    case Event::Ambient: {
                        const int slice = e.shape < 0 ? m_model.background_slot() : m_model.slots(e.shape).La;
                        R += e.shape < 0 ? terms.background : terms.La[e.shape];
                        add(slice, d * e.beta);
                        break;
                    }
                    case Event::Light: {
                        if (e.first && (e.visible != gate_shadowed)) {
                            R += terms.Lc[e.shape];
                            add(m_model.slots(e.shape).Lc, d * e.beta);
                        }
                        if (e.nee && e.visible) {
                            const L& le = m_model.spectra().radiance[e.emitter];
                            R += e.local * le;
                            add(emitter_slice(e.emitter), d * e.beta * e.local);
                            const auto& keys = m_model.slots(e.shape).bsdf;
                            for (size_t k = 0; k < keys.size() && k < kMaxKeys; ++k) add(keys[k].second, d * e.beta * e.grad[k] * le);
                            add_scalar(e.shape, d * e.beta * e.sgrad * le);
                        }
                        break;
                    }
                    case Event::Bounce: {
                        const auto& keys = m_model.slots(e.shape).bsdf;
                        for (size_t k = 0; k < keys.size() && k < kMaxKeys; ++k) add(keys[k].second, d * e.beta * e.grad[k] * R);
                        add_scalar(e.shape, d * e.beta * e.sgrad * R);
                        R = e.local * R;
                        break;
                    }
                }
            }
        }
    }

    /// Sums the per-tile buffers in tile order into the ParamStore (deterministic).
    void reduce() {
        std::vector<float>& out = m_model.params().grad_values();
        for (const auto& g : m_tile_grads)
            if (!g.empty())
                for (size_t i = 0; i < out.size(); ++i) out[i] += g[i];
    }

private:
    struct Scratch {
        int tile = 0;
        std::vector<PathEvents> paths;
        std::vector<std::pair<uint32_t, size_t>> pending;
    };

    int emitter_slice(int emitter) const {
        if (emitter == m_model.scene().environment) return m_model.environment_slot();
        return m_model.slots(m_model.scene().emitters[emitter].shape).Le;
    }

    void push(uint32_t slot, const Event& e) { t_current->paths[slot].events.push_back(e); }

    LatentModel& m_model;
    const std::vector<float>& m_d_image;
    float m_inv_spp;
    std::vector<std::vector<float>> m_tile_grads;
    tbb::enumerable_thread_specific<Scratch> m_scratch;
    static thread_local Scratch* t_current;
};

thread_local Adjoint::Scratch* Adjoint::t_current = nullptr;

}  // namespace

std::vector<float> backward_latent(LatentModel& model, const RenderOptions& opt, const std::vector<float>& d_image, RenderStats* stats) {
    const Scene& scene = model.scene();
    const int w = opt.width > 0 ? opt.width : scene.camera.width, h = opt.height > 0 ? opt.height : scene.camera.height;
    if (d_image.size() != size_t(w) * h * kLatentChannels)
        throw std::invalid_argument("backward_latent: d_image has " + std::to_string(d_image.size()) + " floats, expected " +
                                    std::to_string(size_t(w) * h * kLatentChannels));
    const int n_tiles = ((w + 15) / 16) * ((h + 15) / 16);  // integrators/path.cpp's kTile
    Adjoint adjoint(model, opt, d_image, w, n_tiles);
    TermFilms<kLatentChannels> films = render_latent_terms<kLatentChannels>(scene, model.spectra(), model.terms(), opt, stats, &adjoint);
    adjoint.reduce();
    return films.sum();
}

}  // namespace lpt
