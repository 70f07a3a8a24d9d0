#include "integrators/aov.h"
#include "core/sampler.h"
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

namespace lpt {

AovImages render_aovs(const Scene& scene, const SceneSpectra<3>& spectra, int width, int height, int spp, uint64_t seed,
                      SamplerKind sampler) {
    Camera camera = scene.camera.with_resolution(width, height);
    AovImages out;
    out.width = width;
    out.height = height;
    out.normal.assign(size_t(width) * height * 3, 0.f);
    out.distance.assign(size_t(width) * height, 0.f);
    out.albedo.assign(size_t(width) * height * 3, 0.f);
    tbb::parallel_for(0, height, [&](int y) {
        set_ftz_daz();
        for (int x = 0; x < width; ++x) {
            uint32_t pixel = uint32_t(y * width + x);
            Vec3f n_sum = Vec3f::Zero(), a_sum = Vec3f::Zero();
            float d_sum = 0.f;
            for (int s = 0; s < spp; ++s) {
                SampleStream rng{seed, pixel, uint32_t(s), sampler};
                Vec2f u;
                rng.get2(dim::kFilter, u.x(), u.y());
                Vec2f off = camera.filter.sample(u);
                Ray r = camera.generate_ray(Vec2f(x + 0.5f + off.x(), y + 0.5f + off.y()));
                SurfaceInteraction si = scene.intersect(r);
                if (!si.valid()) continue;
                // Face the viewer: two-sided surfaces' stored winding is arbitrary, and the refiner
                // should see the side the camera sees.
                n_sum += si.sh.n.dot(r.d) > 0.f ? Vec3f(-si.sh.n) : si.sh.n;
                d_sum += si.t;
                BSDFContext ctx;
                ctx.uv = si.uv;
                a_sum += spectra.bsdf_of(scene, si.shape).albedo(ctx).matrix();
            }
            float inv = 1.f / float(spp);
            for (int c = 0; c < 3; ++c) {
                out.normal[pixel * 3 + c] = n_sum[c] * inv;
                out.albedo[pixel * 3 + c] = a_sum[c] * inv;
            }
            out.distance[pixel] = d_sum * inv;
        }
    });
    return out;
}

namespace {

/// Calls hit(pixel, sub-cell, ray, first hit) for every camera ray of a regular grid: each pixel
/// split into cells × cells sub-cells (row-major), rays_per_side² rays in each; rows in parallel.
template <class Hit>
void trace_pixel_grid(const Scene& scene, int width, int height, int cells, int rays_per_side, Hit hit) {
    const Camera camera = scene.camera.with_resolution(width, height);
    const int n = rays_per_side;
    tbb::parallel_for(0, height, [&](int y) {
        set_ftz_daz();
        for (int x = 0; x < width; ++x)
            for (int cy = 0; cy < cells; ++cy)
                for (int cx = 0; cx < cells; ++cx)
                    for (int j = 0; j < n; ++j)
                        for (int i = 0; i < n; ++i) {
                            Vec2f film(x + (cx + (i + 0.5f) / n) / cells, y + (cy + (j + 0.5f) / n) / cells);
                            const Ray ray = camera.generate_ray(film);
                            hit(size_t(y) * width + x, cy * cells + cx, ray, scene.intersect(ray));
                        }
    });
}

}  // namespace

std::vector<float> render_emitter_cells(const Scene& scene, int width, int height, int cells, int rays_per_side) {
    const int k = cells * cells;
    std::vector<int> hits(size_t(width) * height * k, 0);
    trace_pixel_grid(scene, width, height, cells, rays_per_side,
                     [&](size_t p, int cell, const Ray&, const SurfaceInteraction& si) {
                         hits[p * k + cell] += si.valid() && scene.shapes[si.shape].emitter >= 0;
                     });
    std::vector<float> out(hits.size());
    for (size_t i = 0; i < hits.size(); ++i) out[i] = float(hits[i]) / float(rays_per_side * rays_per_side);
    return out;
}

std::vector<float> render_shape_coverage(const Scene& scene, int width, int height, const std::vector<int>& shapes,
                                         int rays_per_side) {
    const size_t k = shapes.size();
    std::vector<float> out(size_t(width) * height * k, 0.f);
    trace_pixel_grid(scene, width, height, 1, rays_per_side,
                     [&](size_t p, int, const Ray&, const SurfaceInteraction& si) {
                         for (size_t s = 0; s < k; ++s)
                             if (si.shape == shapes[s]) out[p * k + s] += 1.f / float(rays_per_side * rays_per_side);
                     });
    return out;
}

CameraSights camera_sights(const Scene& scene, const SceneSpectra<3>& spectra, int width, int height,
                           int rays_per_side) {
    std::vector<char> scatters_below(scene.shapes.size());
    for (size_t s = 0; s < scene.shapes.size(); ++s)
        scatters_below[s] = spectra.bsdf_of(scene, int(s)).scatters_from_below();
    struct Tally {  // per thread; integers, so that the sum does not depend on the threads' order
        std::vector<char> front_of;
        uint64_t black_back_rays = 0;
        bool nothing = false;
    };
    tbb::combinable<Tally> tallies([&] { return Tally{std::vector<char>(scene.shapes.size(), 0)}; });
    trace_pixel_grid(scene, width, height, 1, rays_per_side,
                     [&](size_t, int, const Ray& r, const SurfaceInteraction& si) {
                         Tally& mine = tallies.local();
                         if (!si.valid()) {
                             mine.nothing = true;
                             return;
                         }
                         // the path tracer's sides: an emitter's shading normal is its emission normal
                         const bool front = si.sh.n.dot(-r.d) > 0.f;
                         if (front) mine.front_of[size_t(si.shape)] = 1;
                         if (!front && !scatters_below[size_t(si.shape)]) ++mine.black_back_rays;
                     });
    CameraSights all;
    all.front_of.assign(scene.shapes.size(), 0);
    uint64_t black_back_rays = 0;
    tallies.combine_each([&](const Tally& t) {
        for (size_t s = 0; s < t.front_of.size(); ++s) all.front_of[s] |= t.front_of[s];
        black_back_rays += t.black_back_rays;
        all.nothing |= t.nothing;
    });
    all.black_back_pixels = float(double(black_back_rays) / double(rays_per_side * rays_per_side));
    return all;
}

}  // namespace lpt
