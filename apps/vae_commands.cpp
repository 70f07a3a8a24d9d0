// `latentpt encode | decode | viz`, and the encoded RGB reference that `fit --encode` fits to.
// This file and fit's target path are where the apps touch the VAE (libtorch stays in vae/).
#include "apps/commands.h"
#include "apps/fit_folder.h"
#include "core/image_io.h"
#include "core/latent_viz.h"
#include "core/scene_loader.h"
#include "integrators/path.h"
#include "vae/vae.h"
#include <nlohmann/json.hpp>
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

std::string shared_dir() {
    const char* env = std::getenv("LATENTPT_SHARED");
    return env ? std::string(env) : std::string(LPT_SOURCE_DIR) + "/../shared";
}

std::string default_vae_dir(const std::string& dir) { return dir.empty() ? shared_dir() + "/models/taesd3" : dir; }

std::string default_lpips_dir(const std::string& dir) { return dir.empty() ? shared_dir() + "/models/lpips" : dir; }

float display_value(float v, const std::string& tone) {
    v = tone == "reinhard" ? std::abs(v) / (1.f + std::abs(v)) : std::clamp(v, 0.f, 1.f);
    return std::pow(v, 1.f / 2.2f);
}

namespace {

std::vector<float> rgb_of(const Image& img, const std::string& path) {
    if (img.channels < 3) throw std::runtime_error(path + ": needs 3 channels (RGB), has " + std::to_string(img.channels));
    std::vector<float> rgb(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = img.data[i * img.channels + c];
    return rgb;
}

}  // namespace

std::unique_ptr<Vae> open_vae(const VaeSource& s) {
    if (!s.torchscript()) return load_taesd(default_vae_dir(s.dir));
    if (s.encoder.empty() || s.decoder.empty() || s.config.empty())
        throw std::invalid_argument("a TorchScript VAE needs all of --vae-encoder, --vae-decoder and --vae-config");
    return load_torchscript_vae(s.encoder, s.decoder, s.config);
}

bool vae_present(const VaeSource& s) {
    if (s.torchscript()) return fs::exists(s.encoder) && fs::exists(s.decoder) && fs::exists(s.config);
    return fs::exists(fs::path(default_vae_dir(s.dir)) / "taesd3_decoder.safetensors");
}

VaeSource manifest_vae(const std::string& path) {
    try {
        return vae_source_of(nlohmann::json::parse(read_file(path)));
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(path + ": malformed: " + e.what());
    }
}

VaeSource vae_source_of(const nlohmann::json& m) {
    VaeSource s;
    s.dir = m.value("vae_dir", default_vae_dir(""));
    if (m.contains("vae_torchscript")) {
        const auto& t = m["vae_torchscript"];
        s.encoder = t.value("encoder", "");
        s.decoder = t.value("decoder", "");
        s.config = t.value("config", "");
    }
    return s;
}

std::vector<float> encoded_reference_of(const Scene& scene, int width, int height, int spp, const std::string& tone, const Vae& vae,
                                        bool quiet, const std::string& save_png, std::vector<float>* display_rgb) {
    const int f = vae.convention().downsample;
    if (width % f || height % f)
        throw std::invalid_argument("reference resolution must be a multiple of " + std::to_string(f) + " in both axes, got " + std::to_string(width) + "x" + std::to_string(height));
    SceneSpectra<3> spectra = SceneSpectra<3>::from_description(scene);
    RenderOptions o = RenderOptions::from_scene(scene);
    o.width = width;
    o.height = height;
    o.spp = spp;
    o.seed = 0x5eed;
    RenderStats st;
    std::vector<float> rgb = render_path<3>(scene, spectra, o, &st).develop();
    for (float& v : rgb) v = display_value(v, tone);
    if (!quiet) std::cerr << "reference: " << width << "x" << height << " at " << spp << " spp in " << st.seconds << " s\n";
    if (!save_png.empty()) write_png_display(save_png, Image{width, height, 3, rgb, {}});
    if (display_rgb) *display_rgb = rgb;
    return vae.encode(rgb, width, height);
}

int run_encode(const VaeArgs& a) {
    Image img = read_image(a.input);
    auto vae = open_vae(a.vae);
    // Files hold display values in [0, 1] (PNG/JPEG) or linear radiance (EXR): TAESD wants the former.
    std::vector<float> rgb = rgb_of(img, a.input);
    std::string ext = fs::path(a.input).extension().string();
    if (ext == ".exr" || ext == ".hdr")
        for (float& v : rgb) v = linear_to_srgb(v);
    std::vector<float> latent = vae->encode(rgb, img.width, img.height);
    const int c = vae->convention().channels, w = img.width / vae->convention().downsample, h = img.height / vae->convention().downsample;
    write_exr(a.out, Image{w, h, c, latent, {}});
    if (!a.quiet) std::cerr << "wrote " << a.out << " (" << w << "x" << h << "x" << c << ")\n";
    return 0;
}

int run_decode(const VaeArgs& a) {
    Image lat = read_image(a.input);
    auto vae = open_vae(a.vae);
    if (lat.channels != vae->convention().channels)
        throw std::runtime_error(a.input + ": " + std::to_string(lat.channels) + " channels, the VAE's latents have " + std::to_string(vae->convention().channels));
    std::vector<float> rgb = vae->decode(lat.data, lat.width, lat.height);
    // Decoded values are display-referred (about [0, 1]): EXR keeps them unclamped, PNG as they are.
    const int f = vae->convention().downsample;
    Image out{lat.width * f, lat.height * f, 3, rgb, {"R", "G", "B"}};
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
