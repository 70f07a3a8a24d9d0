// The bounce loop: each stage drains one queue and fills others, so the code reads like the
// algorithm. Stages per depth: intersect → resolve hits (escaped | emitter hit → shade queue)
// → sample lights (NEE → shadow queue) → sample BSDFs (+ Russian roulette → next ray queue)
// → trace shadow rays → swap ray queues. Short per-stage loops also let the CPU overlap paths.
// Equations: docs/transport.md (1)–(4). Random dimensions: core/sampler.h.
#include "integrators/path.h"
#include "core/sampler.h"
#include "integrators/wavefront_state.h"
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <atomic>
#include <chrono>
#include <mutex>

namespace lpt {

RenderOptions RenderOptions::from_scene(const Scene& scene) {
    RenderOptions o;
    o.spp = scene.integrator.spp;
    o.max_depth = scene.integrator.max_depth;
    o.rr_depth = scene.integrator.rr_depth;
    return o;
}

namespace {

constexpr int kTile = 16;              // tile side in pixels: one task owns a tile's pixels
constexpr size_t kWavefront = 4096;    // paths advanced together

template <int N>
struct Workspace {
    RayArrays rays[2];
    ShadowQueue<N> shadow;
    ShadeQueue shade;
    PathState<N> paths;
    std::vector<uint32_t> queue[2];
};

template <int N>
class PathTracer {
public:
    PathTracer(const Scene& scene, const SceneSpectra<N>& spectra, const RenderOptions& opt, const Camera& camera)
        : m_scene(scene), m_spectra(spectra), m_opt(opt), m_camera(camera) {}

    /// Traces samples [s0, s0 + count) of every pixel in [x0,x1)×[y0,y1) and adds them to film.
    void trace_tile(Workspace<N>& ws, Film<N>& film, int x0, int y0, int x1, int y1, int s0, int count, RenderStats& st) const {
        const int tile_pixels = (x1 - x0) * (y1 - y0);
        const size_t n = size_t(tile_pixels) * count;
        ws.paths.resize(n);
        generate_camera_rays(ws, x0, y0, x1, s0, count, n, st);
        int cur = 0;
        for (int depth = 0; !ws.queue[cur].empty(); ++depth) {
            RayArrays& rays = ws.rays[cur];
            rays.intersect(m_scene.rtc(), depth == 0);
            ws.shadow.clear();
            ws.rays[1 - cur].clear();
            ws.queue[1 - cur].clear();
            resolve_hits(ws, cur, depth);
            if (m_opt.strategy != LightStrategy::Bsdf && !m_scene.lights.empty()) sample_lights(ws, depth);
            sample_bsdfs(ws, cur, depth);
            trace_shadow_rays(ws, st);
            st.extension_rays += ws.rays[1 - cur].size;
            cur = 1 - cur;
        }
        for (size_t k = 0; k < n; ++k) film.add_sample(int(ws.paths.pixel[k]), ws.paths.radiance[k]);
    }

private:
    void generate_camera_rays(Workspace<N>& ws, int x0, int y0, int x1, int s0, int count, size_t n, RenderStats& st) const {
        PathState<N>& p = ws.paths;
        ws.rays[0].clear();
        ws.queue[0].clear();
        const int w = x1 - x0;
        const Vec2f tan_half = m_camera.tan_half_fov();
        for (size_t k = 0; k < n; ++k) {
            int local = int(k) / count;
            int x = x0 + local % w, y = y0 + local / w;
            p.pixel[k] = uint32_t(y * m_camera.width + x);
            p.sample[k] = uint32_t(s0 + int(k) % count);
            SampleStream rng{m_opt.seed, p.pixel[k], p.sample[k]};
            Vec2f offset = m_camera.filter.sample(Vec2f(rng.get(dim::kFilter), rng.get(dim::kFilter + 1)));
            Ray r = m_camera.generate_ray(Vec2f(x + 0.5f + offset.x(), y + 0.5f + offset.y()), tan_half);
            p.beta[k].setOnes();
            p.radiance[k].setZero();
            p.prev_pdf[k] = 0.f;
            p.prev_delta[k] = 1;  // a camera ray sees emitters with full weight, like a delta bounce
            p.prev_p[k] = r.o;
            ws.rays[0].push(r.o, r.d, r.tmin, r.tmax);
            ws.queue[0].push_back(uint32_t(k));
        }
        st.camera_rays += n;
    }

    /// docs/transport.md (3): weight of an emitter reached by BSDF sampling.
    float hit_weight(const PathState<N>& p, uint32_t slot, float light_pdf) const {
        if (p.prev_delta[slot] || m_opt.strategy == LightStrategy::Bsdf) return 1.f;
        if (m_opt.strategy == LightStrategy::Nee) return 0.f;
        return mis_power(p.prev_pdf[slot], light_pdf);
    }

    /// Stage 1: escaped rays and emitter hits collect emission (docs/transport.md (3)); vertices
    /// allowed another segment go to the shade queue.
    void resolve_hits(Workspace<N>& ws, int cur, int depth) const {
        PathState<N>& p = ws.paths;
        const RayArrays& rays = ws.rays[cur];
        ShadeQueue& sq = ws.shade;
        sq.reset(rays.size);
        const bool may_continue = m_opt.max_depth < 0 || depth + 1 < m_opt.max_depth;
        const int env = m_scene.environment;
        for (size_t i = 0; i < rays.size; ++i) {
            const uint32_t slot = ws.queue[cur][i];
            if (!rays.hit(i)) {
                if (env < 0) continue;
                float w = hit_weight(p, slot, m_scene.lights.pmf(env) * pdf_constant_light());
                if (w > 0.f) p.radiance[slot] += p.beta[slot] * (w * m_spectra.radiance[env]);
                continue;
            }
            const int shape_id = int(rays.geom[i]);
            const Shape& shape = m_scene.shapes[shape_id];
            SurfaceInteraction si = shape.interaction(rays.prim[i], rays.u[i], rays.v[i], rays.tfar[i]);
            const Vec3f wi_world = -rays.direction(i);
            if (shape.emitter >= 0) {
                Vec3f ne = shape.emission_normal(rays.prim[i], rays.u[i], rays.v[i]);
                if (ne.dot(wi_world) > 0.f) {
                    float light_pdf = m_scene.lights.pmf(shape.emitter) * pdf_area_light(shape, p.prev_p[slot], si.p, ne);
                    float w = hit_weight(p, slot, light_pdf);
                    if (w > 0.f) p.radiance[slot] += p.beta[slot] * (w * m_spectra.radiance[shape.emitter]);
                }
            }
            if (!may_continue) continue;
            const size_t k = sq.count++;
            sq.slot[k] = slot;
            sq.shape[k] = shape_id;
            sq.p[k] = si.p;
            sq.ng[k] = si.ng;
            sq.wi[k] = si.sh.to_local(wi_world);
            sq.frame[k] = si.sh;
            sq.uv[k] = si.uv;
        }
    }

    /// Stage 2: next-event estimation (docs/transport.md (2)) for every non-delta vertex.
    void sample_lights(Workspace<N>& ws, int depth) const {
        PathState<N>& p = ws.paths;
        const ShadeQueue& sq = ws.shade;
        for (size_t k = 0; k < sq.size(); ++k) {
            if (m_spectra.is_delta(m_scene, sq.shape[k])) continue;
            const BSDF<N>& bsdf = m_spectra.bsdf_of(m_scene, sq.shape[k]);
            const uint32_t slot = sq.slot[k];
            SampleStream rng{m_opt.seed, p.pixel[slot], p.sample[slot]};
            LightSample ls = m_scene.lights.sample(m_scene.emitters, m_scene.shapes, sq.p[k], rng.get(dim::bounce(depth, dim::kLightChoice)),
                                                   Vec2f(rng.get(dim::bounce(depth, dim::kLightPos)), rng.get(dim::bounce(depth, dim::kLightPos + 1))));
            if (!ls.valid()) continue;
            BSDFContext ctx;
            ctx.uv = sq.uv[k];
            const Vec3f wo = sq.frame[k].to_local(ls.wi);
            Spectrum<N> f = bsdf.eval(ctx, sq.wi[k], wo);
            if (!(f != 0.f).any()) continue;
            float w = m_opt.strategy == LightStrategy::Nee ? 1.f : mis_power(ls.pdf, bsdf.pdf(ctx, sq.wi[k], wo));
            // Aim from the offset origin at the light point itself: reusing ls.wi from the
            // un-offset point makes the ray cross the light's plane before tmax and hit the light
            // (up to half the NEE energy lost under large, close lights).
            Vec3f o = offset_ray_origin(sq.p[k], sq.ng[k], ls.wi);
            Vec3f dir = ls.wi;
            float tmax = kInf;
            if (m_scene.emitters[ls.emitter].kind != EmitterKind::Constant) {
                Vec3f d = ls.p - o;
                float dist = d.norm();
                dir = d / dist;
                tmax = dist * (1.f - 1e-4f);
            }
            ws.shadow.rays.push(o, dir, 0.f, tmax);
            ws.shadow.slot.push_back(slot);
            ws.shadow.contribution.push_back(p.beta[slot] * f * m_spectra.radiance[ls.emitter] * (w / ls.pdf));
        }
    }

    /// Stage 3: BSDF sampling (docs/transport.md (1)) and Russian roulette (4) → next rays.
    void sample_bsdfs(Workspace<N>& ws, int cur, int depth) const {
        PathState<N>& p = ws.paths;
        const ShadeQueue& sq = ws.shade;
        for (size_t k = 0; k < sq.size(); ++k) {
            const uint32_t slot = sq.slot[k];
            const BSDF<N>& bsdf = m_spectra.bsdf_of(m_scene, sq.shape[k]);
            SampleStream rng{m_opt.seed, p.pixel[slot], p.sample[slot]};
            BSDFContext ctx;
            ctx.uv = sq.uv[k];
            BSDFSample<N> bs = bsdf.sample(ctx, sq.wi[k], rng.get(dim::bounce(depth, dim::kBsdfLobe)),
                                           Vec2f(rng.get(dim::bounce(depth, dim::kBsdfDir)), rng.get(dim::bounce(depth, dim::kBsdfDir + 1))));
            if (!bs.valid()) continue;
            Spectrum<N> beta = p.beta[slot] * bs.weight;
            // |throughput|: sign-safe for latent spectra.
            if (depth + 1 >= m_opt.rr_depth) {
                float q = std::min(beta.abs().maxCoeff(), 0.95f);
                if (rng.get(dim::bounce(depth, dim::kRR)) >= q) continue;
                beta /= q;
            }
            if (!(beta != 0.f).any()) continue;
            const Vec3f wo_world = sq.frame[k].to_world(bs.wo);
            p.beta[slot] = beta;
            p.prev_pdf[slot] = bs.pdf;
            p.prev_delta[slot] = (bs.lobe & kDelta) != 0;
            p.prev_p[slot] = sq.p[k];
            ws.rays[1 - cur].push(offset_ray_origin(sq.p[k], sq.ng[k], wo_world), wo_world, 0.f, kInf);
            ws.queue[1 - cur].push_back(slot);
        }
    }

    void trace_shadow_rays(Workspace<N>& ws, RenderStats& st) const {
        ShadowQueue<N>& sq = ws.shadow;
        sq.rays.occluded(m_scene.rtc());
        st.shadow_rays += sq.rays.size;
        for (size_t j = 0; j < sq.rays.size; ++j)
            if (!sq.rays.blocked(j)) ws.paths.radiance[sq.slot[j]] += sq.contribution[j];
    }

    const Scene& m_scene;
    const SceneSpectra<N>& m_spectra;
    const RenderOptions& m_opt;
    const Camera& m_camera;
};

}  // namespace

template <int N>
Film<N> render_path(const Scene& scene, const SceneSpectra<N>& spectra, const RenderOptions& opt, RenderStats* stats) {
    auto t0 = std::chrono::steady_clock::now();
    Camera camera = scene.camera.with_resolution(opt.width > 0 ? opt.width : scene.camera.width,
                                                 opt.height > 0 ? opt.height : scene.camera.height);
    Film<N> film(camera.width, camera.height);
    const int tiles_x = (camera.width + kTile - 1) / kTile, tiles_y = (camera.height + kTile - 1) / kTile;
    const int n_tiles = tiles_x * tiles_y;
    tbb::enumerable_thread_specific<Workspace<N>> workspaces;
    std::atomic<int> tiles_done{0};
    std::atomic<uint64_t> rays_done{0};
    std::mutex stats_mutex;
    RenderStats total;

    tbb::parallel_for(0, n_tiles, [&](int t) {
        set_ftz_daz();
        Workspace<N>& ws = workspaces.local();
        int x0 = (t % tiles_x) * kTile, y0 = (t / tiles_x) * kTile;
        int x1 = std::min(x0 + kTile, camera.width), y1 = std::min(y0 + kTile, camera.height);
        int per_chunk = std::max(1, int(kWavefront / size_t((x1 - x0) * (y1 - y0))));
        RenderStats st;
        for (int s0 = 0; s0 < opt.spp; s0 += per_chunk) {
            PathTracer<N> tracer(scene, spectra, opt, camera);
            tracer.trace_tile(ws, film, x0, y0, x1, y1, s0, std::min(per_chunk, opt.spp - s0), st);
        }
        {
            std::lock_guard<std::mutex> lock(stats_mutex);
            total.camera_rays += st.camera_rays;
            total.extension_rays += st.extension_rays;
            total.shadow_rays += st.shadow_rays;
        }
        uint64_t r = rays_done += st.rays();
        int done = ++tiles_done;
        if (opt.progress) opt.progress(double(done) / n_tiles, r);
    });
    total.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (stats) *stats = total;
    return film;
}

template Film<3> render_path<3>(const Scene&, const SceneSpectra<3>&, const RenderOptions&, RenderStats*);
template Film<16> render_path<16>(const Scene&, const SceneSpectra<16>&, const RenderOptions&, RenderStats*);

}  // namespace lpt
