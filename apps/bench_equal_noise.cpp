// `latentpt bench --equal-noise`: samples per pixel and render seconds each sampler needs to reach
// one noise level (docs/sampling.md, "Equal noise"). Noise = emitter-masked relMSE against a
// converged reference (docs/validation.md (3)); target = the independent sampler's noise at
// --target-spp. Each sampler renders a ladder of spp (--seeds renders per point, relMSE averaged),
// and the spp and seconds to the target are interpolated log-log between the two points around it.
// scripts/bench_equal_noise.py adds Blender Cycles to the same table.
#include "apps/commands.h"
#include "apps/render_stack_io.h"
#include "core/image_compare.h"
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "integrators/path.h"
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>

namespace lpt::app {

namespace {

struct LadderPoint {
    int spp = 0;
    double seconds = 0, rel_mse = 0;  ///< means over the seeds
};

/// (spp, seconds) at which the ladder's log-log interpolated noise reaches `target`.
std::optional<std::pair<double, double>> reach(const std::vector<LadderPoint>& l, double target) {
    if (!l.empty() && l.front().rel_mse <= target) return std::pair{double(l.front().spp), l.front().seconds};
    for (size_t i = 0; i + 1 < l.size(); ++i) {
        const LadderPoint &a = l[i], &b = l[i + 1];
        if (!(a.rel_mse >= target && target >= b.rel_mse && b.rel_mse > 0 && a.rel_mse != b.rel_mse)) continue;
        const double f = std::log(a.rel_mse / target) / std::log(a.rel_mse / b.rel_mse);
        const double spp = std::exp(std::log(double(a.spp)) + f * std::log(double(b.spp) / a.spp));
        return std::pair{spp, a.seconds + (b.seconds - a.seconds) * (spp - a.spp) / double(b.spp - a.spp)};
    }
    return std::nullopt;
}

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return buf;
}

std::string default_reference(const std::string& scene) {
    const std::filesystem::path p = std::filesystem::path(scene).parent_path() / "TungstenRender.exr";
    if (!std::filesystem::exists(p))
        throw std::runtime_error(scene +
                                 ": no converged reference beside it (TungstenRender.exr); give one with --reference");
    return p.string();
}

}  // namespace

int run_bench_equal_noise(const BenchArgs& a) {
    const std::string scene_path = a.scene.empty() ? shared_dir() + "/scenes/cornell-box/scene_v3.xml" : a.scene;
    const std::string ref_path = a.reference.empty() ? default_reference(scene_path) : a.reference;
    if (a.seeds < 1) throw std::invalid_argument("--seeds must be >= 1");
    const Scene scene = load_scene(scene_path);
    const SceneSpectra<3> spectra = SceneSpectra<3>::from_description(scene);
    const RenderStack ref = load_stack({ref_path}, a.res);
    if (ref.width != a.res || ref.height != a.res)
        throw std::runtime_error(ref_path + ": " + std::to_string(ref.width) + "x" + std::to_string(ref.height) +
                                 " after downsampling, not " + std::to_string(a.res) + "x" + std::to_string(a.res));
    const std::vector<uint8_t> mask = emitter_mask(scene, a.res, a.res);
    const std::vector<int> ladder = {4, 8, 16, 32, 64, 128, 256};

    std::vector<std::pair<SamplerKind, std::vector<LadderPoint>>> ladders;
    for (SamplerKind sampler : {SamplerKind::Independent, SamplerKind::Sobol}) {
        std::vector<LadderPoint> points;
        for (int spp : ladder) {
            LadderPoint p{spp, 0, 0};
            for (int seed = 1; seed <= a.seeds; ++seed) {
                RenderOptions opt = RenderOptions::from_scene(scene);
                opt.sampler = sampler;
                opt.spp = spp;
                opt.seed = uint64_t(seed);
                opt.width = opt.height = a.res;
                RenderStats stats;
                RenderStack test{a.res, a.res, {render_path<3>(scene, spectra, opt, &stats).develop()}};
                p.seconds += stats.seconds / a.seeds;
                p.rel_mse += compare_renders(test, ref, mask).rel_mse / a.seeds;
            }
            std::fprintf(stderr, "equal-noise: %-11s %4d spp  %7.2f s  relMSE %.6f\n", sampler_name(sampler), spp,
                         p.seconds, p.rel_mse);
            points.push_back(p);
        }
        ladders.push_back({sampler, points});
    }
    double target = -1;
    for (const LadderPoint& p : ladders.front().second)
        if (p.spp == a.target_spp) target = p.rel_mse;
    if (target < 0) throw std::invalid_argument("--target-spp must be one of 4, 8, ..., 256");

    const auto independent = reach(ladders[0].second, target), sobol = reach(ladders[1].second, target);
    std::printf("equal noise: %s at %dx%d, target relMSE %.6f (independent at %d spp); reference %s\n",
                scene_path.c_str(), a.res, a.res, target, a.target_spp, ref_path.c_str());
    std::printf("%-12s %14s %18s\n", "sampler", "spp to target", "seconds to target");
    for (const auto& [name, r] : {std::pair{"independent", independent}, std::pair{"sobol", sobol}}) {
        if (r) std::printf("%-12s %14.1f %18.2f\n", name, r->first, r->second);
        else std::printf("%-12s %14s %18s\n", name, "not reached", "-");
    }
    if (independent && sobol)
        std::printf("sobol: %.2fx fewer spp, %.2fx faster than independent (render times only, %d seed(s) per point)\n",
                    independent->first / sobol->first, independent->second / sobol->second, a.seeds);
    if (!a.out_json.empty()) {
        std::string js = "{\"scene\":\"" + scene_path + "\",\"res\":" + std::to_string(a.res) +
                         ",\"target\":" + num(target) + ",\"target_spp\":" + std::to_string(a.target_spp) +
                         ",\"ladders\":{";
        for (size_t k = 0; k < ladders.size(); ++k) {
            js += std::string(k ? "," : "") + "\"" + sampler_name(ladders[k].first) + "\":[";
            for (size_t i = 0; i < ladders[k].second.size(); ++i) {
                const LadderPoint& p = ladders[k].second[i];
                js += std::string(i ? "," : "") + "[" + std::to_string(p.spp) + "," + num(p.seconds) + "," +
                      num(p.rel_mse) + "]";
            }
            js += "]";
        }
        js += "}}\n";
        write_text_atomic(a.out_json, js);
    }
    return 0;
}

}  // namespace lpt::app
