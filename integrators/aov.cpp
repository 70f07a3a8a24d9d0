#include "integrators/aov.h"
#include "core/sampler.h"
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

std::vector<float> render_emitter_cells(const Scene& scene, int width, int height, int cells, int rays_per_side) {
    Camera camera = scene.camera.with_resolution(width, height);
    const int k = cells * cells, n = rays_per_side;
    std::vector<float> out(size_t(width) * height * k, 0.f);
    tbb::parallel_for(0, height, [&](int y) {
        set_ftz_daz();
        for (int x = 0; x < width; ++x)
            for (int cy = 0; cy < cells; ++cy)
                for (int cx = 0; cx < cells; ++cx) {
                    int hits = 0;
                    for (int j = 0; j < n; ++j)
                        for (int i = 0; i < n; ++i) {
                            Vec2f film(x + (cx + (i + 0.5f) / n) / cells, y + (cy + (j + 0.5f) / n) / cells);
                            SurfaceInteraction si = scene.intersect(camera.generate_ray(film));
                            hits += si.valid() && scene.shapes[si.shape].emitter >= 0;
                        }
                    out[(size_t(y) * width + x) * k + cy * cells + cx] = float(hits) / float(n * n);
                }
    });
    return out;
}

std::vector<float> render_shape_coverage(const Scene& scene, int width, int height, const std::vector<int>& shapes,
                                         int rays_per_side) {
    Camera camera = scene.camera.with_resolution(width, height);
    const int k = int(shapes.size()), n = rays_per_side;
    std::vector<float> out(size_t(width) * height * k, 0.f);
    tbb::parallel_for(0, height, [&](int y) {
        set_ftz_daz();
        for (int x = 0; x < width; ++x)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const SurfaceInteraction si =
                        scene.intersect(camera.generate_ray(Vec2f(x + (i + 0.5f) / n, y + (j + 0.5f) / n)));
                    for (int s = 0; s < k; ++s)
                        if (si.shape == shapes[s]) out[(size_t(y) * width + x) * k + s] += 1.f / float(n * n);
                }
    });
    return out;
}

}  // namespace lpt
