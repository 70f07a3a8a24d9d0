// Recording (a PathObserver) and the two sweeps over recorded paths. docs/path-replay.md (1)–(6).
#include "autodiff/path_record.h"
#include "core/sampler.h"
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <stdexcept>

namespace lpt {

using L = Latent;

size_t PathRecords::events() const {
    size_t n = 0;
    for (const auto& t : tiles)
        for (const PathBlock& b : t) n += b.events.size();
    return n;
}

size_t PathRecords::bytes() const {
    size_t n = 0;
    for (const auto& t : tiles)
        for (const PathBlock& b : t)
            n += b.events.capacity() * sizeof(PathEvent) +
                 (b.pixel.capacity() + b.sample.capacity() + b.begin.capacity()) * sizeof(uint32_t);
    return n;
}

namespace detail {

struct PathRecorder::Scratch {
    int tile = 0;
    std::vector<std::vector<PathEvent>> paths;           ///< per slot, in event order
    std::vector<std::pair<uint32_t, uint32_t>> pending;  ///< shadow id → (slot, event index)
    PathBlock block;                                     ///< reused when complete() keeps nothing
};

struct PathRecorder::Threads {
    tbb::enumerable_thread_specific<Scratch> local;
};

namespace {

/// Every hook of a wavefront runs on the thread that called begin() (path_observer.h), so each
/// thread remembers the scratch of the wavefront it is recording, per recorder: two recorders
/// that take turns on one thread (nested renders, two fits) each find their own.
struct CurrentScratch {
    const void* recorder = nullptr;
    void* scratch = nullptr;
};
thread_local CurrentScratch t_current;

}  // namespace

PathRecorder::Scratch& PathRecorder::scratch() const {
    if (t_current.recorder != this) t_current = {this, &m_threads->local.local()};
    return *static_cast<Scratch*>(t_current.scratch);
}

PathRecorder::PathRecorder(int n_tiles) : m_threads(std::make_unique<Threads>()), m_records(n_tiles) {}
PathRecorder::~PathRecorder() = default;

void PathRecorder::begin(int tile, size_t n) {
    t_current = {this, &m_threads->local.local()};
    Scratch& s = scratch();
    s.tile = tile;
    if (s.paths.size() < n) s.paths.resize(n);
    for (size_t i = 0; i < n; ++i) s.paths[i].clear();
}

void PathRecorder::emission(uint32_t slot, int emitter, float mis) {
    PathEvent e;
    e.type = PathEvent::Emission;
    e.emitter = emitter;
    e.mis = mis;
    scratch().paths[slot].push_back(e);
}

void PathRecorder::ambient(uint32_t slot, int shape) {
    PathEvent e;
    e.type = PathEvent::Ambient;
    e.shape = shape;
    scratch().paths[slot].push_back(e);
}

void PathRecorder::light_sample(uint32_t slot, int shadow_id, int shape, int emitter, float w_over_pdf,
                                const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, bool nee, bool first) {
    PathEvent e;
    e.type = PathEvent::Light;
    e.shape = shape;
    e.emitter = emitter;
    e.flags = uint8_t((nee ? PathEvent::kNee : 0) | (first ? PathEvent::kFirst : 0));
    e.w_over_pdf = w_over_pdf;
    e.uv = ctx.uv;
    e.wi = wi;
    e.wo = wo;
    Scratch& s = scratch();
    if (shadow_id >= 0) {
        if (s.pending.size() <= size_t(shadow_id)) s.pending.resize(shadow_id + 1);
        s.pending[shadow_id] = {slot, uint32_t(s.paths[slot].size())};
    }
    s.paths[slot].push_back(e);
}

void PathRecorder::shadow(int shadow_id, bool blocked) {
    Scratch& s = scratch();
    auto [slot, idx] = s.pending[shadow_id];
    if (!blocked) s.paths[slot][idx].flags |= PathEvent::kVisible;
}

void PathRecorder::bounce(uint32_t slot, int shape, const BSDFContext& ctx, const Vec3f& wi,
                          const BSDFSample<kLatentChannels>& bs, float q, int depth) {
    PathEvent e;
    e.type = PathEvent::Bounce;
    e.shape = shape;
    e.survival = q;
    e.lobe = uint8_t(bs.lobe);
    e.depth = uint8_t(depth);
    e.pdf = bs.pdf;
    e.eta = bs.eta;
    e.uv = ctx.uv;
    e.wi = wi;
    e.wo = bs.wo;
    scratch().paths[slot].push_back(e);
}

void PathRecorder::end(const uint32_t* pixel, const uint32_t* sample, size_t n) {
    Scratch& s = scratch();
    PathBlock& b = s.block;
    b.pixel.assign(pixel, pixel + n);
    b.sample.assign(sample, sample + n);
    b.begin.resize(n + 1);
    b.events.clear();
    for (size_t k = 0; k < n; ++k) {
        b.begin[k] = uint32_t(b.events.size());
        b.events.insert(b.events.end(), s.paths[k].begin(), s.paths[k].end());
    }
    b.begin[n] = uint32_t(b.events.size());
    complete(s.tile, b);
}

namespace {

/// Per-thread buffers of one path's sweep.
struct PathScratch {
    std::vector<L, Eigen::aligned_allocator<L>> beta, local;
};

BSDFContext context_of(const PathEvent& e) {
    BSDFContext ctx;
    ctx.uv = e.uv;
    return ctx;
}

BSDFSample<kLatentChannels> sample_of(const PathEvent& e) {
    BSDFSample<kLatentChannels> bs;
    bs.wo = e.wo;
    bs.pdf = e.pdf;
    bs.eta = e.eta;
    bs.lobe = e.lobe;
    return bs;
}

/// docs/path-replay.md (6): a bounce's weight with the current coefficients. Non-delta lobes:
/// f·|cos|/p with the recorded direction and pdf. Delta lobes have no density to divide by, so
/// the BSDF samples again with the path's own random numbers: its lobe choice and direction
/// depend on geometry only (core/bsdf.h), so it returns the recorded lobe with today's value.
L bounce_weight(const BSDF<kLatentChannels>& bsdf, const PathEvent& e, SamplerId sampler, uint32_t pixel,
                uint32_t sample) {
    if (e.lobe & kDelta) {
        const BsdfRandoms u = bsdf_randoms(sampler.stream(pixel, sample), e.depth);
        BSDFSample<kLatentChannels> bs = bsdf.sample(context_of(e), e.wi, u.lobe, Vec2f(u.dir[0], u.dir[1]));
        return bs.lobe == e.lobe ? L(bs.weight) : L::Zero();
    }
    return bsdf.eval(context_of(e), e.wi, e.wo) / e.pdf;
}

/// Throughput in front of each event (beta) and each event's local factor (local): a visible
/// NEE sample's BSDF value f, a bounce's weight/q. docs/path-replay.md (1).
void sweep_forward(const LatentModel& m, SamplerId sampler, uint32_t pixel, uint32_t sample, const PathEvent* ev,
                   size_t n, PathScratch& s) {
    if (s.beta.size() < n) {
        s.beta.resize(n);
        s.local.resize(n);
    }
    L beta = L::Ones();
    for (size_t i = 0; i < n; ++i) {
        const PathEvent& e = ev[i];
        s.beta[i] = beta;
        if (e.type == PathEvent::Light && (e.flags & PathEvent::kNee) && (e.flags & PathEvent::kVisible)) {
            s.local[i] = m.spectra().bsdf_of(m.scene(), e.shape).eval(context_of(e), e.wi, e.wo);
        } else if (e.type == PathEvent::Bounce) {
            s.local[i] = bounce_weight(m.spectra().bsdf_of(m.scene(), e.shape), e, sampler, pixel, sample) / e.survival;
            beta *= s.local[i];
        }
    }
}

bool gate_open(const LatentModel& m, const PathEvent& e) {
    return (e.flags & PathEvent::kFirst) && occlusion_gate_passes(m.terms().gate, (e.flags & PathEvent::kVisible) != 0);
}

bool visible_nee(const PathEvent& e) { return (e.flags & PathEvent::kNee) && (e.flags & PathEvent::kVisible); }

int emitter_slice(const LatentModel& m, int emitter) {
    if (emitter == m.scene().environment) return m.environment_slot();
    return m.slots(m.scene().emitters[emitter].shape).Le;
}

/// A thread_local, not a static enumerable_thread_specific: that one would be destroyed after
/// TBB's own teardown at exit.
PathScratch& path_scratch() {
    thread_local PathScratch s;
    return s;
}

}  // namespace

void backward_block(const LatentModel& m, SamplerId sampler, const PathBlock& block, const float* d_image,
                    float inv_spp, float* g) {
    const ParamStore& ps = m.params();
    const auto& terms = m.terms();
    const auto& radiance = m.spectra().radiance;
    PathScratch& s = path_scratch();
    auto add = [&](int slice, const L& v) {
        if (slice >= 0) Eigen::Map<L>(g + ps.slice(slice).value_offset) += v;
    };
    for (size_t k = 0; k < block.paths(); ++k) {
        const PathEvent* ev = block.events.data() + block.begin[k];
        const size_t n = block.begin[k + 1] - block.begin[k];
        if (n == 0) continue;
        sweep_forward(m, sampler, block.pixel[k], block.sample[k], ev, n, s);
        const L d = Eigen::Map<const L>(d_image + size_t(block.pixel[k]) * kLatentChannels) * inv_spp;
        // A scalar parameter (roughness) scales every channel: its derivative sums them.
        auto add_scalar = [&](int shape, const L& v) {
            const auto& sc = m.slots(shape).scalar;
            if (!sc.empty()) g[ps.slice(sc[0].second).value_offset] += v.sum();
        };
        L R = L::Zero();  // docs/path-replay.md (3): what the events after i add, with β = 1 at i
        const L one = L::Ones();
        for (size_t i = n; i-- > 0;) {
            const PathEvent& e = ev[i];
            const L& beta = s.beta[i];
            switch (e.type) {
                case PathEvent::Emission:
                    R += emission_score(one, e.mis, radiance[e.emitter]);
                    add(emitter_slice(m, e.emitter), d * beta * e.mis);
                    break;
                case PathEvent::Ambient:
                    R += ambient_score(one, e.shape < 0 ? terms.background : terms.La[e.shape]);
                    add(e.shape < 0 ? m.background_slot() : m.slots(e.shape).La, d * beta);
                    break;
                case PathEvent::Light: {
                    if (gate_open(m, e)) {
                        R += occlusion_score(one, terms.Lc[e.shape]);
                        add(m.slots(e.shape).Lc, d * beta);
                    }
                    if (!visible_nee(e)) break;
                    const L& le = radiance[e.emitter];
                    R += nee_score(one, s.local[i], le, e.w_over_pdf);
                    add(emitter_slice(m, e.emitter), d * beta * s.local[i] * e.w_over_pdf);
                    const BSDF<kLatentChannels>& bsdf = m.spectra().bsdf_of(m.scene(), e.shape);
                    const BSDFContext ctx = context_of(e);
                    const auto& keys = m.slots(e.shape).bsdf;
                    for (size_t c = 0; c < keys.size(); ++c)
                        add(keys[c].second, d * beta * bsdf.eval_grad(ctx, e.wi, e.wo, int(c)) * (e.w_over_pdf * le));
                    if (!m.slots(e.shape).scalar.empty())
                        add_scalar(e.shape, d * beta * bsdf.eval_grad_scalar(ctx, e.wi, e.wo, 0) * (e.w_over_pdf * le));
                    break;
                }
                case PathEvent::Bounce: {
                    const BSDF<kLatentChannels>& bsdf = m.spectra().bsdf_of(m.scene(), e.shape);
                    const BSDFContext ctx = context_of(e);
                    const BSDFSample<kLatentChannels> bs = sample_of(e);
                    const float inv_q = 1.f / e.survival;
                    const auto& keys = m.slots(e.shape).bsdf;
                    for (size_t c = 0; c < keys.size(); ++c)
                        add(keys[c].second, d * beta * bsdf.weight_grad(ctx, e.wi, bs, int(c)) * (inv_q * R));
                    if (!m.slots(e.shape).scalar.empty() && !(e.lobe & kDelta))
                        add_scalar(e.shape, d * beta * bsdf.weight_grad_scalar(ctx, e.wi, bs, 0) * (inv_q * R));
                    R = s.local[i] * R;
                    break;
                }
            }
        }
    }
}

}  // namespace detail

PathRecords record_latent_paths(const LatentModel& model, const RenderOptions& opt, std::vector<float>* image,
                                RenderStats* stats) {
    const Scene& scene = model.scene();
    PathRecords r;
    r.sampler = {opt.seed, opt.sampler};
    r.width = opt.width > 0 ? opt.width : scene.camera.width;
    r.height = opt.height > 0 ? opt.height : scene.camera.height;
    r.spp = opt.spp;
    detail::PathRecorder recorder(render_tile_count(r.width, r.height));
    TermFilms<kLatentChannels> films =
        render_latent_terms<kLatentChannels>(scene, model.spectra(), model.terms(), opt, stats, &recorder);
    if (image) *image = films.sum();
    r.tiles = std::move(recorder.records());
    return r;
}

std::vector<float> replay_forward(const LatentModel& m, const PathRecords& r) {
    TermFilms<kLatentChannels> films{Film<kLatentChannels>(r.width, r.height), Film<kLatentChannels>(r.width, r.height),
                                     Film<kLatentChannels>(r.width, r.height)};
    const auto& terms = m.terms();
    const auto& radiance = m.spectra().radiance;
    // A tile's pixels belong to its blocks only: tiles run in parallel without sharing a pixel.
    tbb::parallel_for(0, int(r.tiles.size()), [&](int t) {
        detail::PathScratch& s = detail::path_scratch();
        for (const PathBlock& block : r.tiles[t]) {
            for (size_t k = 0; k < block.paths(); ++k) {
                const PathEvent* ev = block.events.data() + block.begin[k];
                const size_t n = block.begin[k + 1] - block.begin[k];
                L e_sum = L::Zero(), a_sum = L::Zero(), c_sum = L::Zero();
                detail::sweep_forward(m, r.sampler, block.pixel[k], block.sample[k], ev, n, s);
                for (size_t i = 0; i < n; ++i) {
                    const PathEvent& e = ev[i];
                    const L& beta = s.beta[i];
                    if (e.type == PathEvent::Emission) {
                        e_sum += emission_score(beta, e.mis, radiance[e.emitter]);
                    } else if (e.type == PathEvent::Ambient) {
                        a_sum += ambient_score(beta, e.shape < 0 ? terms.background : terms.La[e.shape]);
                    } else if (e.type == PathEvent::Light) {
                        if (detail::gate_open(m, e)) c_sum += occlusion_score(beta, terms.Lc[e.shape]);
                        if (detail::visible_nee(e))
                            e_sum += nee_score(beta, s.local[i], radiance[e.emitter], e.w_over_pdf);
                    }
                }
                films.e.add_sample(int(block.pixel[k]), e_sum);
                films.a.add_sample(int(block.pixel[k]), a_sum);
                films.c.add_sample(int(block.pixel[k]), c_sum);
            }
        }
    });
    return films.sum();
}

void replay_backward(LatentModel& m, const PathRecords& r, const std::vector<float>& d_image) {
    if (d_image.size() != size_t(r.width) * r.height * kLatentChannels)
        throw std::invalid_argument("replay_backward: d_image has " + std::to_string(d_image.size()) +
                                    " floats, expected " +
                                    std::to_string(size_t(r.width) * r.height * kLatentChannels));
    const size_t n_values = m.params().grad_values().size();
    std::vector<std::vector<float>> tile_grads(r.tiles.size());
    tbb::parallel_for(0, int(r.tiles.size()), [&](int t) {
        if (r.tiles[t].empty()) return;
        tile_grads[t].assign(n_values, 0.f);
        for (const PathBlock& block : r.tiles[t])
            detail::backward_block(m, r.sampler, block, d_image.data(), 1.f / float(r.spp), tile_grads[t].data());
    });
    // Summed in tile order: bit-identical at any thread count (docs/path-replay.md (5)).
    std::vector<float>& out = m.params().grad_values();
    for (const auto& g : tile_grads)
        for (size_t i = 0; i < g.size(); ++i) out[i] += g[i];
}

}  // namespace lpt
