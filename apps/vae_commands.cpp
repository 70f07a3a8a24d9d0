// `latentpt encode | decode | viz`, and the encoded RGB reference that `fit --encode` fits to.
// This file and fit's target path are where the apps touch the VAE (libtorch stays in vae/).
#include "apps/commands.h"
#include "core/image_io.h"
#include "core/latent_viz.h"
#include "core/scene_loader.h"
#include "integrators/path.h"
#include "vae/vae.h"
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#ifndef LPT_SOURCE_DIR
#define LPT_SOURCE_DIR "."
#endif

namespace lpt::app {

namespace fs = std::filesystem;

std::string default_vae_dir(const std::string& dir) {
    if (!dir.empty()) return dir;
    const char* env = std::getenv("LATENTPT_SHARED");
    return (env ? std::string(env) : std::string(LPT_SOURCE_DIR) + "/../shared") + "/models/taesd3";
}

std::string default_lpips_dir(const std::string& dir) {
    if (!dir.empty()) return dir;
    const char* env = std::getenv("LATENTPT_SHARED");
    return (env ? std::string(env) : std::string(LPT_SOURCE_DIR) + "/../shared") + "/models/lpips";
}

namespace {

/// The paper's display mapping for references: clip to [0, 1] or |x|/(1+|x|), then x^(1/2.2).
float display(float v, const std::string& tone) {
    v = tone == "reinhard" ? std::abs(v) / (1.f + std::abs(v)) : std::clamp(v, 0.f, 1.f);
    return std::pow(v, 1.f / 2.2f);
}

std::vector<float> rgb_of(const Image& img, const std::string& path) {
    if (img.channels < 3) throw std::runtime_error(path + ": needs 3 channels (RGB), has " + std::to_string(img.channels));
    std::vector<float> rgb(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = img.data[i * img.channels + c];
    return rgb;
}

}  // namespace

std::vector<float> encoded_reference_of(const Scene& scene, int width, int height, int spp, const std::string& tone, const std::string& vae_dir,
                                        bool quiet, const std::string& save_png, std::vector<float>* display_rgb) {
    if (width % 8 || height % 8) throw std::invalid_argument("reference resolution must be a multiple of 8 in both axes, got " + std::to_string(width) + "x" + std::to_string(height));
    auto vae = load_taesd(default_vae_dir(vae_dir));
    SceneSpectra<3> spectra = SceneSpectra<3>::from_description(scene);
    RenderOptions o = RenderOptions::from_scene(scene);
    o.width = width;
    o.height = height;
    o.spp = spp;
    o.seed = 0x5eed;
    RenderStats st;
    std::vector<float> rgb = render_path<3>(scene, spectra, o, &st).develop();
    for (float& v : rgb) v = display(v, tone);
    if (!quiet) std::cerr << "reference: " << width << "x" << height << " at " << spp << " spp in " << st.seconds << " s\n";
    if (!save_png.empty()) write_png_display(save_png, Image{width, height, 3, rgb, {}});
    if (display_rgb) *display_rgb = rgb;
    return vae->encode(rgb, width, height);
}

std::vector<float> encoded_reference(const std::string& scene_path, const std::map<std::string, std::string>& defines, int width,
                                     int height, int spp, const std::string& tone, const std::string& vae_dir, bool quiet,
                                     const std::string& save_png) {
    Scene scene = load_scene(scene_path, defines);
    return encoded_reference_of(scene, width, height, spp, tone, vae_dir, quiet, save_png);
}

int run_encode(const VaeArgs& a) {
    Image img = read_image(a.input);
    auto vae = load_taesd(default_vae_dir(a.vae_dir));
    // Files hold display values in [0, 1] (PNG/JPEG) or linear radiance (EXR): TAESD wants the former.
    std::vector<float> rgb = rgb_of(img, a.input);
    std::string ext = fs::path(a.input).extension().string();
    if (ext == ".exr" || ext == ".hdr")
        for (float& v : rgb) v = linear_to_srgb(v);
    std::vector<float> latent = vae->encode(rgb, img.width, img.height);
    const int c = vae->convention().channels, w = img.width / 8, h = img.height / 8;
    write_exr(a.out, Image{w, h, c, latent, {}});
    if (!a.quiet) std::cerr << "wrote " << a.out << " (" << w << "x" << h << "x" << c << ")\n";
    return 0;
}

int run_decode(const VaeArgs& a) {
    Image lat = read_image(a.input);
    auto vae = load_taesd(default_vae_dir(a.vae_dir));
    if (lat.channels != vae->convention().channels)
        throw std::runtime_error(a.input + ": " + std::to_string(lat.channels) + " channels, the VAE's latents have " + std::to_string(vae->convention().channels));
    std::vector<float> rgb = vae->decode(lat.data, lat.width, lat.height);
    // Decoded values are display-referred (about [0, 1]): EXR keeps them unclamped, PNG as they are.
    Image out{lat.width * 8, lat.height * 8, 3, rgb, {"R", "G", "B"}};
    if (fs::path(a.out).extension() == ".exr") write_exr(a.out, out);
    else write_png_display(a.out, out);
    if (!a.quiet) std::cerr << "wrote " << a.out << " (" << out.width << "x" << out.height << ")\n";
    return 0;
}

int run_viz(const VaeArgs& a) {
    Image lat = read_image(a.input);
    write_png_srgb(a.out, latent_grid(lat.data.data(), lat.width, lat.height, lat.channels));
    if (!a.quiet) std::cerr << "wrote " << a.out << "\n";
    return 0;
}

}  // namespace lpt::app
