// `latentpt render`: scene → float EXR + sRGB PNG preview (+ AOV EXRs).
#include "apps/commands.h"
#include "core/film.h"
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "integrators/aov.h"
#include "integrators/path.h"
#include <filesystem>
#include <iostream>
#include <mutex>

namespace lpt::app {

namespace {
constexpr int kPngMaxSide = 1000000;  // PNG_USER_WIDTH_MAX and PNG_USER_HEIGHT_MAX

std::string with_suffix(const std::string& exr_path, const std::string& suffix_ext) {
    std::filesystem::path p(exr_path);
    return (p.parent_path() / (p.stem().string() + suffix_ext)).string();
}
}  // namespace

int run_render(const RenderArgs& a) {
    Scene scene = load_scene(a.scene, a.defines, a.sampler);
    SceneSpectra<3> spectra = SceneSpectra<3>::from_description(scene);
    RenderOptions opt = RenderOptions::from_scene(scene);
    opt.seed = a.seed;
    if (a.spp > 0) opt.spp = a.spp;
    if (a.max_depth != -2) opt.max_depth = a.max_depth;
    if (!a.res.empty()) parse_resolution(a.res, opt.width, opt.height, "--res");
    {  // before the render: a size found too large after it cost the render (or left the EXR alone)
        const int w = opt.width > 0 ? opt.width : scene.camera.width,
                  h = opt.height > 0 ? opt.height : scene.camera.height;
        const char* flag = a.res.empty() ? "the scene's camera" : "--res";
        pipeline::check_size_fits(w, h, 2 * 3 + 1, flag);  // the film's floats a pixel
        if (w > kPngMaxSide || h > kPngMaxSide)            // libpng's limit: the EXR would be written, its preview not
            throw std::invalid_argument(std::string(flag) + ": " + std::to_string(w) + "x" + std::to_string(h) +
                                        " is beyond the PNG preview's " + std::to_string(kPngMaxSide) +
                                        " pixels a side");
    }
    // the AOVs' size is checked before the render, not found too large after it
    int aw = opt.width, ah = opt.height;
    if (a.aov && !a.aov_res.empty()) {
        parse_resolution(a.aov_res, aw, ah, "--aov-res");
        pipeline::check_size_fits(aw, ah, 7, "--aov-res");  // normal, distance, albedo
    }
    opt.strategy = a.strategy == "nee"    ? LightStrategy::Nee
                   : a.strategy == "bsdf" ? LightStrategy::Bsdf
                                          : LightStrategy::Mis;
    Progress progress("render", !a.quiet);
    std::mutex m;
    opt.progress = [&](double f, uint64_t rays) {
        std::lock_guard<std::mutex> lock(m);
        progress.update(f, rays);
    };
    RenderStats stats;
    Film<3> film = render_path<3>(scene, spectra, opt, &stats);
    progress.finish(stats.rays());

    Image img{film.width(), film.height(), 3, film.develop(), {"R", "G", "B"}};
    write_exr(a.out, img);
    write_png_srgb(with_suffix(a.out, ".png"), img, a.exposure);
    if (a.aov) {
        AovImages aov = render_aovs(scene, spectra, aw, ah, std::min(opt.spp, 16), a.seed, opt.sampler);
        write_exr(with_suffix(a.out, ".normal.exr"), Image{aov.width, aov.height, 3, aov.normal, {"X", "Y", "Z"}});
        write_exr(with_suffix(a.out, ".distance.exr"), Image{aov.width, aov.height, 1, aov.distance, {"Z"}});
        write_exr(with_suffix(a.out, ".albedo.exr"), Image{aov.width, aov.height, 3, aov.albedo, {"R", "G", "B"}});
    }
    if (!a.quiet)
        std::cerr << "wrote " << a.out << " and " << with_suffix(a.out, ".png") << " (" << img.width << "x"
                  << img.height << ", " << opt.spp << " spp, " << stats.rays() << " rays, " << stats.seconds << " s)\n";
    return 0;
}

}  // namespace lpt::app
