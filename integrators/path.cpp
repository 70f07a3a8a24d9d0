// The driver: splits the image into tiles, one task each, and runs the tracer's bounce loop
// (integrators/path_tracer.h) over each tile's samples in wavefronts. Pixels belong to exactly
// one tile and their random numbers to the pixel, so the image does not depend on the thread
// count.
#include "integrators/path.h"
#include "integrators/path_tracer.h"
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <atomic>
#include <chrono>
#include <mutex>

namespace lpt {

namespace {

constexpr int kTile = 16;            // tile side in pixels: one task owns a tile's pixels
constexpr size_t kWavefront = 4096;  // paths advanced together

/// Shared driver: tiles in parallel, each tile's pixels owned by one task (deterministic).
template <int N>
void render_tiles(const Scene& scene, const SceneSpectra<N>& spectra, const LatentTerms<N>* terms,
                  PathObserver<N>* observer, const RenderOptions& opt, const Camera& camera, Film<N>* const films[3],
                  RenderStats* stats) {
    auto t0 = std::chrono::steady_clock::now();
    const int tiles_x = (camera.width + kTile - 1) / kTile, tiles_y = (camera.height + kTile - 1) / kTile;
    const int n_tiles = tiles_x * tiles_y;
    tbb::enumerable_thread_specific<TileWorkspace<N>> workspaces;
    std::atomic<int> tiles_done{0};
    std::atomic<uint64_t> rays_done{0};
    std::mutex stats_mutex;
    RenderStats total;
    const PathTracer<N> tracer(scene, spectra, opt, camera, terms, observer);

    tbb::parallel_for(0, n_tiles, [&](int t) {
        set_ftz_daz();
        TileWorkspace<N>& ws = workspaces.local();
        int x0 = (t % tiles_x) * kTile, y0 = (t / tiles_x) * kTile;
        int x1 = std::min(x0 + kTile, camera.width), y1 = std::min(y0 + kTile, camera.height);
        int per_chunk = std::max(1, int(kWavefront / size_t((x1 - x0) * (y1 - y0))));
        RenderStats st;
        for (int s0 = 0; s0 < opt.spp; s0 += per_chunk)
            tracer.trace_tile(ws, films, t, x0, y0, x1, y1, s0, std::min(per_chunk, opt.spp - s0), st);
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
}

}  // namespace

int render_tile_count(int width, int height) { return ((width + kTile - 1) / kTile) * ((height + kTile - 1) / kTile); }

namespace {

Camera render_camera(const Scene& scene, const RenderOptions& opt) {
    return scene.camera.with_resolution(opt.width > 0 ? opt.width : scene.camera.width,
                                        opt.height > 0 ? opt.height : scene.camera.height);
}

}  // namespace

template <int N>
Film<N> render_path(const Scene& scene, const SceneSpectra<N>& spectra, const RenderOptions& opt, RenderStats* stats) {
    Camera camera = render_camera(scene, opt);
    Film<N> film(camera.width, camera.height);
    Film<N>* const films[3] = {&film, nullptr, nullptr};
    render_tiles<N>(scene, spectra, nullptr, nullptr, opt, camera, films, stats);
    return film;
}

template <int N>
TermFilms<N> render_latent_terms(const Scene& scene, const SceneSpectra<N>& spectra, const LatentTerms<N>& terms,
                                 const RenderOptions& opt, RenderStats* stats, PathObserver<N>* observer) {
    if (terms.La.size() != scene.shapes.size() || terms.Lc.size() != scene.shapes.size())
        throw std::invalid_argument("render_latent_terms: La/Lc must hold one vector per shape");
    Camera camera = render_camera(scene, opt);
    TermFilms<N> out{Film<N>(camera.width, camera.height), Film<N>(camera.width, camera.height),
                     Film<N>(camera.width, camera.height)};
    Film<N>* const films[3] = {&out.e, &out.a, &out.c};
    render_tiles<N>(scene, spectra, &terms, observer, opt, camera, films, stats);
    return out;
}

template <int N>
std::vector<float> TermFilms<N>::sum() const {
    std::vector<float> s = e.develop(), a_img = a.develop(), c_img = c.develop();
    for (size_t i = 0; i < s.size(); ++i) s[i] += a_img[i] + c_img[i];
    return s;
}

template Film<3> render_path<3>(const Scene&, const SceneSpectra<3>&, const RenderOptions&, RenderStats*);
template Film<16> render_path<16>(const Scene&, const SceneSpectra<16>&, const RenderOptions&, RenderStats*);
template TermFilms<3> render_latent_terms<3>(const Scene&, const SceneSpectra<3>&, const LatentTerms<3>&,
                                             const RenderOptions&, RenderStats*, PathObserver<3>*);
template TermFilms<16> render_latent_terms<16>(const Scene&, const SceneSpectra<16>&, const LatentTerms<16>&,
                                               const RenderOptions&, RenderStats*, PathObserver<16>*);
template struct TermFilms<3>;
template struct TermFilms<16>;

}  // namespace lpt
