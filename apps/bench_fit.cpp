// `latentpt bench --fit`: seconds per fit iteration at latent resolution, forward (primal render
// of Ĩe + Ĩa + Ĩc) and adjoint (path replay) measured separately, for several spp, plus what
// 3000 iterations would take. docs/performance.md records the figures.
#include "apps/commands.h"
#include "autodiff/latent_path_adjoint.h"
#include "autodiff/path_record.h"
#include "core/scene_loader.h"
#include <chrono>
#include <cstdio>
#include <filesystem>

#ifndef LPT_SOURCE_DIR
#define LPT_SOURCE_DIR "."
#endif

namespace lpt::app {

int run_bench_fit(const BenchArgs& a) {
    std::string path = a.fit_scene;
    if (path.empty()) {
        path = shared_dir() + "/scenes/cbox/cbox_specular.xml";
        if (!std::filesystem::exists(path)) path = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json";
    }
    Scene scene = load_scene(path, {}, a.sampler);
    LatentModel model(scene, Parameterisation::Code, 1);
    std::vector<float> d_image(size_t(a.fit_res) * a.fit_res * kLatentChannels, 1e-3f);
    std::printf("scene %s, %dx%d latents x %d channels, max_depth %d, 2 passes per iteration\n", path.c_str(),
                a.fit_res, a.fit_res, kLatentChannels, scene.integrator.max_depth);
    std::printf("%6s %10s %10s %10s %14s | %10s %10s %10s %10s %14s\n", "spp", "forward s", "adjoint s", "total s",
                "3000 it (min)", "record s", "replay f s", "replay b s", "records MB", "K=8: 3000 it");
    for (int spp : a.fit_spp) {
        RenderOptions o = RenderOptions::from_scene(scene);
        o.width = o.height = a.fit_res;
        o.spp = spp;
        const int reps = spp >= 256 ? 2 : 4;
        double fwd = 0, adj = 0, rec = 0, rfwd = 0, rbwd = 0, mb = 0;
        for (int r = 0; r < reps + 1; ++r) {  // the first repetition warms up and is not counted
            o.seed = uint64_t(r);
            auto t0 = std::chrono::steady_clock::now();
            render_latent_terms<kLatentChannels>(model.scene(), model.spectra(), model.terms(), o);
            auto t1 = std::chrono::steady_clock::now();
            model.params().zero_grad();
            backward_latent(model, o, d_image);
            auto t2 = std::chrono::steady_clock::now();
            // --reuse-paths: record once (primal included), then replay without tracing.
            PathRecords records = record_latent_paths(model, o);
            auto t3 = std::chrono::steady_clock::now();
            replay_forward(model, records);
            auto t4 = std::chrono::steady_clock::now();
            model.params().zero_grad();
            replay_backward(model, records, d_image);
            auto t5 = std::chrono::steady_clock::now();
            if (r == 0) continue;
            fwd += std::chrono::duration<double>(t1 - t0).count() / reps;
            adj += std::chrono::duration<double>(t2 - t1).count() / reps;
            rec += std::chrono::duration<double>(t3 - t2).count() / reps;
            rfwd += std::chrono::duration<double>(t4 - t3).count() / reps;
            rbwd += std::chrono::duration<double>(t5 - t4).count() / reps;
            mb = double(records.bytes()) / (1 << 20);
        }
        // K = 8: one recording iteration (record + backward replay) per seven replay-only ones.
        const double k8 = (rec + rbwd + 7 * (rfwd + rbwd)) / 8;
        std::printf("%6d %10.3f %10.3f %10.3f %14.1f | %10.3f %10.3f %10.3f %10.0f %14.1f\n", spp, fwd, adj, fwd + adj,
                    3000 * (fwd + adj) / 60, rec, rfwd, rbwd, mb, 3000 * k8 / 60);
    }
    return 0;
}

}  // namespace lpt::app
