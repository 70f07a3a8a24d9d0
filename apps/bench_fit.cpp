// `latentpt bench --fit`: seconds per fit iteration at latent resolution, forward (primal render
// of Ĩe + Ĩa + Ĩc) and adjoint (path replay) measured separately, for several spp, plus what
// 3000 iterations would take. docs/performance.md records the figures.
#include "apps/commands.h"
#include "autodiff/latent_path_adjoint.h"
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
        const char* env = std::getenv("LATENTPT_SHARED");
        std::string shared = env ? env : std::string(LPT_SOURCE_DIR) + "/../shared";
        path = shared + "/scenes/cbox/cbox_specular.xml";
        if (!std::filesystem::exists(path)) path = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json";
    }
    Scene scene = load_scene(path);
    LatentModel model(scene, Parameterisation::Code, 1);
    std::vector<float> d_image(size_t(a.fit_res) * a.fit_res * kLatentChannels, 1e-3f);
    std::printf("scene %s, %dx%d latents x %d channels, max_depth %d, 2 passes per iteration\n", path.c_str(), a.fit_res, a.fit_res, kLatentChannels,
                scene.integrator.max_depth);
    std::printf("%6s %12s %12s %12s %16s\n", "spp", "forward s", "adjoint s", "total s", "3000 it (min)");
    for (int spp : a.fit_spp) {
        RenderOptions o = RenderOptions::from_scene(scene);
        o.width = o.height = a.fit_res;
        o.spp = spp;
        const int reps = spp >= 256 ? 2 : 4;
        double fwd = 0, adj = 0;
        for (int r = 0; r < reps + 1; ++r) {  // the first repetition warms up and is not counted
            o.seed = uint64_t(r);
            auto t0 = std::chrono::steady_clock::now();
            render_latent_terms<kLatentChannels>(model.scene(), model.spectra(), model.terms(), o);
            auto t1 = std::chrono::steady_clock::now();
            model.params().zero_grad();
            backward_latent(model, o, d_image);
            auto t2 = std::chrono::steady_clock::now();
            if (r == 0) continue;
            fwd += std::chrono::duration<double>(t1 - t0).count() / reps;
            adj += std::chrono::duration<double>(t2 - t1).count() / reps;
        }
        std::printf("%6d %12.3f %12.3f %12.3f %16.1f\n", spp, fwd, adj, fwd + adj, 3000 * (fwd + adj) / 60);
    }
    return 0;
}

}  // namespace lpt::app
