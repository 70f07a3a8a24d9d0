#include "pipeline/refiner_io.h"
#include "core/image_io.h"
#include "integrators/aov.h"
#include "latent/latent.h"
#include "pipeline/fit_folder.h"
#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace lpt::pipeline {

RefinerInput refiner_view(const Scene& scene, std::vector<float> latent, int w, int h, int spp, uint64_t seed) {
    AovImages aov = render_aovs(scene, SceneSpectra<3>::from_description(scene), w, h, spp, seed);
    RefinerInput in;
    in.width = w;
    in.height = h;
    in.latent = std::move(latent);
    in.normal = std::move(aov.normal);
    in.distance = std::move(aov.distance);
    return in;
}

RefinerInput fit_refiner_view(const FitFolder& fit, const RefinerConfig& config, int w, int h, int spp, uint64_t seed) {
    RefinerInput in;
    if (config.terms) {
        FitRender r = render_fit_terms(fit, w, h, spp, seed);
        in = refiner_view(*fit.scene, std::move(r.toned), w, h, spp, seed);
        in.terms = std::move(r.terms);
    } else {
        in = refiner_view(*fit.scene, render_fit_latent(fit, w, h, spp, seed), w, h, spp, seed);
    }
    if (config.emitter_cells) in.emitter = render_emitter_cells(*fit.scene, w, h, config.emitter_cells);
    return in;
}

std::vector<float> load_refiner_terms(const std::string& fitdir, int w, int h) {
    std::vector<float> term[3];
    const char* files[3] = {"latent_e.exr", "latent_a.exr", "latent_c.exr"};
    for (int k = 0; k < 3; ++k)
        term[k] = read_fit_image((std::filesystem::path(fitdir) / files[k]).string(), kLatentChannels, w, h).data;
    return interleave_terms(term[0], term[1], term[2], kLatentChannels);
}

void write_refiner_aovs(const std::string& path, const RefinerInput& in) {
    Image img{in.width, in.height, 4, {}, {"N.X", "N.Y", "N.Z", "Z"}};
    for (size_t i = 0; i < in.distance.size(); ++i)
        img.data.insert(img.data.end(), {in.normal[3 * i], in.normal[3 * i + 1], in.normal[3 * i + 2], in.distance[i]});
    write_exr(path, img);
}

RefinerInput load_refiner_input(const std::string& latent_exr, const std::string& aov_exr) {
    Image lat = read_fit_image(latent_exr, kLatentChannels, 0, 0);
    Image aov = read_fit_image(aov_exr, 4, lat.width, lat.height);
    RefinerInput in;
    in.width = lat.width;
    in.height = lat.height;
    in.latent = lat.data;
    // By name: OpenEXR files list Z first whatever order they were written in.
    int idx[4];
    const char* names[4] = {"N.X", "N.Y", "N.Z", "Z"};
    for (int k = 0; k < 4; ++k) {
        auto it = std::find(aov.channel_names.begin(), aov.channel_names.end(), names[k]);
        if (it == aov.channel_names.end())
            throw std::runtime_error(aov_exr + ": no channel '" + names[k] + "' (expected N.X N.Y N.Z Z)");
        idx[k] = int(it - aov.channel_names.begin());
    }
    for (size_t i = 0; i < size_t(lat.width) * lat.height; ++i) {
        in.normal.insert(in.normal.end(),
                         {aov.data[4 * i + idx[0]], aov.data[4 * i + idx[1]], aov.data[4 * i + idx[2]]});
        in.distance.push_back(aov.data[4 * i + idx[3]]);
    }
    return in;
}

}  // namespace lpt::pipeline
