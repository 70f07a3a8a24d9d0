// The bounce loop: each stage drains one queue and fills others, so the code reads like the
// algorithm (integrators/path_tracer.h lists the stages). Short per-stage loops also let the CPU
// overlap paths.
#include "integrators/path_tracer.h"
#include "core/envmap.h"
#include "core/sampler.h"
#include "core/sample_batch.h"
#include "core/warp.h"

namespace lpt {

template <int N>
PathTracer<N>::PathTracer(const Scene& scene, const SceneSpectra<N>& spectra, const RenderOptions& opt,
                          const Camera& camera, const LatentTerms<N>* terms, PathObserver<N>* observer)
    : m_scene(scene),
      m_spectra(spectra),
      m_opt(opt),
      m_camera(camera),
      m_obs(observer),
      m_latent(terms ? std::make_optional<LatentStage<N>>(*terms, observer) : std::nullopt),
      m_emission(!terms || terms->emission),
      m_keep_zero(terms != nullptr) {
    m_lambertian.reserve(scene.shapes.size());
    for (size_t s = 0; s < scene.shapes.size(); ++s) {
        m_lambertian.push_back(spectra.bsdf_of(scene, int(s)).lambertian());
        m_scatters_below.push_back(spectra.bsdf_of(scene, int(s)).scatters_from_below());
    }
}

template <int N>
void PathTracer<N>::trace_tile(TileWorkspace<N>& ws, Film<N>* const films[3], int tile, int x0, int y0, int x1, int y1,
                               int s0, int count, RenderStats& st) const {
    const int tile_pixels = (x1 - x0) * (y1 - y0);
    const size_t n = size_t(tile_pixels) * count;
    ws.paths.resize(n);
    if (m_obs) m_obs->begin(tile, n);
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
    if (m_obs) m_obs->end(ws.paths.pixel.data(), ws.paths.sample.data(), n);
    for (size_t k = 0; k < n; ++k) {
        films[0]->add_sample(int(ws.paths.pixel[k]), ws.paths.radiance[k]);
        if (m_latent) {
            films[1]->add_sample(int(ws.paths.pixel[k]), ws.paths.ambient[k]);
            films[2]->add_sample(int(ws.paths.pixel[k]), ws.paths.occlusion[k]);
        }
    }
}

template <int N>
void PathTracer<N>::generate_camera_rays(TileWorkspace<N>& ws, int x0, int y0, int x1, int s0, int count, size_t n,
                                         RenderStats& st) const {
    PathState<N>& p = ws.paths;
    ws.queue[0].resize(n);
    // Pixel, key and filter randoms per path, then all camera rays at once (Camera::generate_rays)
    // straight into the ray arrays; the filter randoms borrow the BSDF stage's arrays.
    for (auto* a : {&ws.film[0], &ws.film[1], &ws.u_dir[0], &ws.u_dir[1]})
        if (a->size() < n) a->resize(n);
    float *fx = ws.film[0].data(), *fy = ws.film[1].data(), *u0 = ws.u_dir[0].data(), *u1 = ws.u_dir[1].data();
    const int w = x1 - x0;
    for (size_t k = 0; k < n; ++k) {
        int local = int(k) / count;
        int x = x0 + local % w, y = y0 + local / w;
        p.pixel[k] = uint32_t(y * m_camera.width + x);
        p.sample[k] = uint32_t(s0 + int(k) % count);
        const SampleStream rng{m_opt.seed, p.pixel[k], p.sample[k], m_opt.sampler};
        p.key[k] = rng.key;
        fx[k] = float(x);
        fy[k] = float(y);
    }
    sample_batch(m_opt.sampler, p.key.data(), p.sample.data(), n, dim::kFilter, u0, u1);
    RayArrays& rays = ws.rays[0];
    rays.resize_for_fill(n);
    m_camera.generate_rays(n, fx, fy, u0, u1, m_camera.tan_half_fov(),
                           {rays.ox.data(), rays.oy.data(), rays.oz.data(), rays.dx.data(), rays.dy.data(),
                            rays.dz.data(), rays.tnear.data(), rays.tfar.data()});
    for (size_t k = 0; k < n; ++k) {
        p.beta[k].setOnes();
        p.radiance[k].setZero();
        p.ambient[k].setZero();
        p.occlusion[k].setZero();
        p.past_first[k] = 0;
        p.prev_pdf[k] = 0.f;
        p.prev_delta[k] = 1;  // a camera ray sees emitters with full weight, like a delta bounce
        p.prev_p[k] = rays.origin(k);
        ws.queue[0][k] = uint32_t(k);
    }
    st.camera_rays += n;
}

template <int N>
Spectrum<N> PathTracer<N>::emitted(int e, const Vec3f& w, float* factor) const {
    const Emitter& em = m_scene.emitters[e];
    *factor = 1.f;
    if (em.kind != EmitterKind::EnvMap) return m_spectra.radiance[e];
    if constexpr (N == 3) {
        return em.envmap->eval(w);
    } else {
        *factor = em.envmap->relative_luminance(w);
        return m_spectra.radiance[e] * *factor;
    }
}

template <int N>
float PathTracer<N>::hit_weight(const PathState<N>& p, uint32_t slot, float light_pdf) const {
    if (p.prev_delta[slot] || m_opt.strategy == LightStrategy::Bsdf) return 1.f;
    if (m_opt.strategy == LightStrategy::Nee) return 0.f;
    return mis_power(p.prev_pdf[slot], light_pdf);
}

template <int N>
void PathTracer<N>::resolve_hits(TileWorkspace<N>& ws, int cur, int depth) const {
    PathState<N>& p = ws.paths;
    const RayArrays& rays = ws.rays[cur];
    ShadeQueue& sq = ws.shade;
    sq.reset(rays.size);
    const bool may_continue = m_opt.max_depth < 0 || depth + 1 < m_opt.max_depth;
    const int env = m_scene.environment;
    for (size_t i = 0; i < rays.size; ++i) {
        const uint32_t slot = ws.queue[cur][i];
        if (!rays.hit(i)) {
            if (depth == 0 && m_latent && m_latent->camera_look(p, slot, -1)) continue;
            if (m_latent) m_latent->escaped(p, slot);
            if (env < 0 || !m_emission) continue;
            const Vec3f dir = rays.direction(i);
            const Emitter& em = m_scene.emitters[env];
            const float env_pdf = em.kind == EmitterKind::EnvMap ? em.envmap->pdf(dir) : pdf_constant_light();
            float w = hit_weight(p, slot, m_scene.lights.pmf(env) * env_pdf);
            if (w > 0.f) {
                float factor;
                const Spectrum<N> le = emitted(env, dir, &factor);
                p.radiance[slot] += emission_score(p.beta[slot], w, le);
                if (m_obs) m_obs->emission(slot, env, w * factor);
            }
            continue;
        }
        const int shape_id = int(rays.geom[i]);
        const Shape& shape = m_scene.shapes[shape_id];
        SurfaceInteraction si = shape.interaction(rays.prim[i], rays.u[i], rays.v[i], rays.tfar[i]);
        const Vec3f wi_world = -rays.direction(i);
        if (shape.emitter >= 0) {
            const Vec3f& ne = si.sh.n;  // = shape.emission_normal at the hit (Shape::interaction)
            const bool front = ne.dot(wi_world) > 0.f;
            // an emitter the training view never showed, in the look an edit gives it
            if (front && depth == 0 && m_latent && m_latent->camera_look(p, slot, shape_id)) continue;
            if (front && m_emission) {
                float light_pdf = m_scene.lights.pmf(shape.emitter) * pdf_area_light(shape, p.prev_p[slot], si.p, ne);
                float w = hit_weight(p, slot, light_pdf);
                if (w > 0.f) {
                    p.radiance[slot] += emission_score(p.beta[slot], w, m_spectra.radiance[shape.emitter]);
                    if (m_obs) m_obs->emission(slot, shape.emitter, w);
                }
            }
        }
        // Latent: Ĩa at the first non-delta vertex of E S* D; its light sample decides Ĩc.
        // Before it, the back of a one-sided surface scores the background (docs/transport.md (6)),
        // or, seen by a camera ray in an edit that gives black a look, that look: RGB shows it black.
        const bool black_side = !m_scatters_below[shape_id] && si.sh.n.dot(wi_world) <= 0.f;
        if (black_side && depth == 0 && m_latent && m_latent->camera_look_of_black(p, slot)) continue;
        const bool gate_here =
            m_latent && m_latent->hit(p, slot, shape_id, m_spectra.is_delta(m_scene, shape_id), black_side);
        // Without Ĩe nothing is collected after the first non-delta vertex.
        const bool cont = may_continue && (m_emission || !p.past_first[slot]);
        const uint8_t flags = (cont ? ShadeQueue::kContinue : 0) | (gate_here ? ShadeQueue::kFirst : 0);
        if (!flags) continue;
        const size_t k = sq.count++;
        sq.flags[k] = flags;
        sq.slot[k] = slot;
        sq.key[k] = p.key[slot];
        sq.sample[k] = p.sample[slot];
        sq.shape[k] = shape_id;
        sq.p[k] = si.p;
        sq.ng[k] = si.ng;
        sq.wi[k] = si.sh.to_local(wi_world);
        sq.frame[k] = si.sh;
        sq.uv[k] = si.uv;
    }
}

template <int N>
void PathTracer<N>::sample_lights(TileWorkspace<N>& ws, int depth) const {
    PathState<N>& p = ws.paths;
    const ShadeQueue& sq = ws.shade;
    const bool nee_on = m_emission && m_opt.strategy != LightStrategy::Bsdf && !m_scene.lights.empty();
    if (!m_scene.lights.empty()) draw_light_samples(ws, depth);
    for (size_t k = 0; k < sq.size(); ++k) {
        const bool first = (sq.flags[k] & ShadeQueue::kFirst) != 0;
        const bool nee = nee_on && (sq.flags[k] & ShadeQueue::kContinue) && !m_spectra.is_delta(m_scene, sq.shape[k]);
        if (!nee && !first) continue;
        const uint32_t slot = sq.slot[k];
        Spectrum<N> occl = Spectrum<N>::Zero();
        if (first) occl = m_latent->occlusion(p, slot, sq.shape[k]);
        if (m_scene.lights.empty()) {  // no light: everything is in shadow
            if (first) gate_unlit(p, sq, k, occl);
            continue;
        }
        const LightSample ls = ws.lights.get(k);
        // A light sample behind the light, or below the viewer's side of a surface that only
        // reflects, is an attached shadow: V = 0 without tracing. A transmissive surface
        // (rough dielectric) sees lights on both sides.
        const Vec3f wi_world = sq.frame[k].to_world(sq.wi[k]);
        const bool reflects_only = !(m_spectra.bsdf_of(m_scene, sq.shape[k]).flags() & kTransmission);
        if (!ls.valid() || (reflects_only && sq.ng[k].dot(ls.wi) * sq.ng[k].dot(wi_world) <= 0.f)) {
            if (first) gate_unlit(p, sq, k, occl);
            continue;
        }
        Spectrum<N> contribution = Spectrum<N>::Zero();
        BSDFContext ctx;
        ctx.uv = sq.uv[k];
        const Vec3f wo = sq.frame[k].to_local(ls.wi);
        float w_over_pdf = 0.f;
        if (nee) {
            const BSDF<N>& bsdf = m_spectra.bsdf_of(m_scene, sq.shape[k]);
            const Spectrum<N> f = bsdf.eval(ctx, sq.wi[k], wo);
            // A zero f (a latent reflectance at 0) still has a derivative: keep it for the adjoint.
            if ((f != 0.f).any() || m_keep_zero) {
                float w = m_opt.strategy == LightStrategy::Nee ? 1.f : mis_power(ls.pdf, bsdf.pdf(ctx, sq.wi[k], wo));
                float factor;
                const Spectrum<N> le = emitted(ls.emitter, ls.wi, &factor);
                contribution = nee_score(p.beta[slot], f, le, w / ls.pdf);
                w_over_pdf = w / ls.pdf * factor;  // the observer multiplies by radiance[emitter]
            } else if (!first) {
                continue;
            }
        }
        if (m_obs)
            m_obs->light_sample(slot, int(ws.shadow.rays.size), sq.shape[k], ls.emitter, w_over_pdf, ctx, sq.wi[k], wo,
                                nee, first);
        push_shadow_ray(ws.shadow.rays, sq.p[k], sq.ng[k], ls);
        ws.shadow.slot.push_back(slot);
        ws.shadow.contribution.push_back(contribution);
        if (m_latent) ws.shadow.occlusion.push_back(occl);
    }
}

template <int N>
void PathTracer<N>::draw(const ShadeQueue& sq, uint32_t dimension, float* u0, float* u1) const {
    sample_batch(m_opt.sampler, sq.key.data(), sq.sample.data(), sq.size(), dimension, u0, u1);
}

template <int N>
void PathTracer<N>::draw_light_samples(TileWorkspace<N>& ws, int depth) const {
    const ShadeQueue& sq = ws.shade;
    LightBatch& lb = ws.lights;
    lb.resize(sq.size());
    for (size_t k = 0; k < sq.size(); ++k) {
        lb.rx[k] = sq.p[k].x();
        lb.ry[k] = sq.p[k].y();
        lb.rz[k] = sq.p[k].z();
    }
    draw(sq, dim::bounce(depth, dim::kLightChoice), lb.u_choice.data());
    draw(sq, dim::bounce(depth, dim::kLightPos), lb.u_pos0.data(), lb.u_pos1.data());
    m_scene.lights.sample_batch(m_scene.emitters, m_scene.shapes, sq.size(), lb);
}

template <int N>
void PathTracer<N>::gate_unlit(PathState<N>& p, const ShadeQueue& sq, size_t k, const Spectrum<N>& occl) const {
    m_latent->gate(p, sq.slot[k], occl, false);
    if (m_obs)
        m_obs->light_sample(sq.slot[k], -1, sq.shape[k], -1, 0.f, BSDFContext{}, sq.wi[k], sq.wi[k], false, true);
}

template <int N>
void PathTracer<N>::push_shadow_ray(RayArrays& rays, const Vec3f& p, const Vec3f& ng, const LightSample& ls) const {
    Vec3f o = offset_ray_origin(p, ng, ls.wi);
    Vec3f dir = ls.wi;
    float tmax = kInf;
    if (!m_scene.emitters[ls.emitter].is_environment()) {
        Vec3f d = ls.p - o;
        float dist = d.norm();
        dir = d * (1.f / dist);
        tmax = dist * (1.f - 1e-4f);
    }
    rays.push(o, dir, 0.f, tmax);
}

template <int N>
void PathTracer<N>::sample_bsdfs(TileWorkspace<N>& ws, int cur, int depth) const {
    PathState<N>& p = ws.paths;
    const ShadeQueue& sq = ws.shade;
    // Every entry's random numbers and cosine-warped direction first: the warp is a long
    // dependent chain that the batch evaluates 4-8 wide (core/warp.h); Lambertian vertices
    // use it, other BSDFs sample from the same random numbers.
    const size_t n = sq.size();
    for (auto* a : {&ws.u_lobe, &ws.u_dir[0], &ws.u_dir[1], &ws.cosine[0], &ws.cosine[1], &ws.cosine[2]})
        if (a->size() < n) a->resize(n);
    bsdf_randoms_batch(m_opt.sampler, sq.key.data(), sq.sample.data(), n, uint32_t(depth), ws.u_lobe.data(),
                       ws.u_dir[0].data(), ws.u_dir[1].data());
    sample_cosine_hemisphere_batch(ws.u_dir[0].data(), ws.u_dir[1].data(), ws.cosine[0].data(), ws.cosine[1].data(),
                                   ws.cosine[2].data(), n);
    for (size_t k = 0; k < n; ++k) {
        if (!(sq.flags[k] & ShadeQueue::kContinue)) continue;
        const uint32_t slot = sq.slot[k];
        const BSDF<N>& bsdf = m_spectra.bsdf_of(m_scene, sq.shape[k]);
        const SampleStream rng = SampleStream::from_key(p.key[slot], p.sample[slot], m_opt.sampler);
        BSDFContext ctx;
        ctx.uv = sq.uv[k];
        const Lambertian lambertian = m_lambertian[sq.shape[k]];
        const BSDFSample<N> bs =
            lambertian != Lambertian::No
                ? lambertian_sample<N>(lambertian, sq.wi[k], Vec3f(ws.cosine[0][k], ws.cosine[1][k], ws.cosine[2][k]),
                                       bsdf.lambertian_reflectance(ctx))
                : bsdf.sample(ctx, sq.wi[k], ws.u_lobe[k], Vec2f(ws.u_dir[0][k], ws.u_dir[1][k]));
        if (!bs.valid()) continue;
        Spectrum<N> beta = p.beta[slot] * bs.weight;
        // |throughput|: sign-safe for latent spectra.
        float q = 1.f;
        if (depth + 1 >= m_opt.rr_depth) {
            q = std::min(beta.abs().maxCoeff(), 0.95f);
            if (rng.get(dim::bounce(depth, dim::kRR)) >= q) continue;
            beta /= q;
        }
        // A zero throughput contributes nothing but may still have a derivative.
        if (!(beta != 0.f).any() && !m_keep_zero) continue;
        if (m_obs) m_obs->bounce(slot, sq.shape[k], ctx, sq.wi[k], bs, q, depth);
        const Vec3f wo_world = sq.frame[k].to_world(bs.wo);
        p.beta[slot] = beta;
        p.prev_pdf[slot] = bs.pdf;
        p.prev_delta[slot] = (bs.lobe & kDelta) != 0;
        p.prev_p[slot] = sq.p[k];
        ws.rays[1 - cur].push(offset_ray_origin(sq.p[k], sq.ng[k], wo_world), wo_world, 0.f, kInf);
        ws.queue[1 - cur].push_back(slot);
    }
}

template <int N>
void PathTracer<N>::trace_shadow_rays(TileWorkspace<N>& ws, RenderStats& st) const {
    ShadowQueue<N>& sq = ws.shadow;
    sq.rays.occluded(m_scene.rtc());
    st.shadow_rays += sq.rays.size;
    for (size_t j = 0; j < sq.rays.size; ++j) {
        const bool blocked = sq.rays.blocked(j);
        if (m_obs) m_obs->shadow(int(j), blocked);
        if (!blocked) ws.paths.radiance[sq.slot[j]] += sq.contribution[j];
        if (m_latent) m_latent->gate(ws.paths, sq.slot[j], sq.occlusion[j], !blocked);
    }
}

template class PathTracer<3>;
template class PathTracer<16>;

}  // namespace lpt
