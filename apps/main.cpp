// latentpt command line: `latentpt <subcommand> --help` describes each subcommand.
#include "apps/commands.h"
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <iostream>
#include <memory>

int main(int argc, char** argv) {
    using namespace lpt::app;
    CLI::App app{"latentpt: a differentiable path tracer that renders into the latent space of an image autoencoder"};
    app.require_subcommand(1);
    int threads = 0;
    app.add_option("--threads", threads, "worker threads (default: all cores)");

    RenderArgs r;
    std::vector<std::string> defines;
    auto* render = app.add_subcommand("render", "path trace a scene (.json) to a float EXR plus an sRGB PNG preview");
    render->add_option("scene", r.scene, "scene file (.json)")->required()->check(CLI::ExistingFile);
    render->add_option("-o,--out", r.out, "output EXR path; the PNG preview goes beside it")->capture_default_str();
    render->add_option("--spp", r.spp, "samples per pixel (default: the scene's)");
    render->add_option("--res", r.res, "resolution WxH (default: the scene's camera)");
    render->add_option("--seed", r.seed, "random seed: same seed, same image, at any thread count")->capture_default_str();
    render->add_option("--max-depth", r.max_depth, "longest path in segments, -1 = unbounded (default: the scene's)");
    render->add_option("--strategy", r.strategy, "light estimator: mis (NEE + BSDF sampling), nee, bsdf")
        ->check(CLI::IsMember({"mis", "nee", "bsdf"}))->capture_default_str();
    render->add_flag("--aov", r.aov, "also write <out>.normal.exr, <out>.distance.exr, <out>.albedo.exr");
    render->add_option("--aov-res", r.aov_res, "AOV resolution WxH (default: the image's; e.g. image/8 for latents)");
    render->add_option("--exposure", r.exposure, "PNG preview exposure in stops")->capture_default_str();
    render->add_option("-D,--define", defines, "override a scene value, e.g. -D integrator.max_depth=4");
    render->add_flag("-q,--quiet", r.quiet, "no progress line");

    BenchArgs b;
    auto* bench = app.add_subcommand("bench", "rays/s of the path tracer next to raw Embree throughput on the same ray counts");
    bench->add_option("--scene", b.scene, "scene (default: scenes/cornell-box/scene.json)");
    bench->add_option("--spp", b.spp, "samples per pixel")->capture_default_str();
    bench->add_option("--res", b.res, "square resolution")->capture_default_str();
    bench->add_option("--sphere-triangles", b.sphere_triangles, "triangles of the sphere added for the heavy-scene run")->capture_default_str();
    bench->add_option("--json", b.out_json, "also write the results as JSON");

    CLI11_PARSE(app, argc, argv);
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    try {
        if (*render) {
            for (const auto& d : defines) {
                auto eq = d.find('=');
                if (eq == std::string::npos) throw std::invalid_argument("-D expects key=value, got '" + d + "'");
                r.defines[d.substr(0, eq)] = d.substr(eq + 1);
            }
            return run_render(r);
        }
        if (*bench) return run_bench(b);
    } catch (const std::exception& e) {
        std::cerr << "latentpt: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
