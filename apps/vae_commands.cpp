// `latentpt encode | decode`: images to latents and back through the VAE (libtorch stays in
// vae/; this file is part of the torch plugin, apps/torch_commands.h).
#include "apps/commands.h"
#include "core/image_io.h"
#include "pipeline/reference.h"
#include "pipeline/vae_source.h"
#include "vae/vae.h"
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>

namespace lpt::app {

namespace fs = std::filesystem;

namespace {

std::vector<float> rgb_of(const Image& img, const std::string& path) {
    if (img.channels < 3)
        throw std::runtime_error(path + ": needs 3 channels (RGB), has " + std::to_string(img.channels));
    std::vector<float> rgb(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = img.data[i * img.channels + c];
    return rgb;
}

}  // namespace

int run_encode(const VaeArgs& a) {
    Image img = read_image(a.input);
    auto vae = pipeline::open_vae(a.vae);
    // Files hold display values in [0, 1] (PNG/JPEG, EXRs marked so) or linear radiance (other
    // EXRs): TAESD wants the former, mapped as fit maps its references, so that a render's
    // encoding here is the latent fit --encode would target.
    std::vector<float> rgb = rgb_of(img, a.input);
    std::string ext = fs::path(a.input).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    const bool linear = (ext == ".exr" || ext == ".hdr") && !img.display;
    // a decoded EXR overshoots [0, 1]; as a PNG it would have been clipped
    for (float& v : rgb) v = linear ? pipeline::display_value(v, "clip") : std::clamp(v, 0.f, 1.f);
    std::vector<float> latent = vae->encode(rgb, img.width, img.height);
    const int c = vae->convention().channels, w = img.width / vae->convention().downsample,
              h = img.height / vae->convention().downsample;
    write_exr(a.out, Image{w, h, c, latent, {}});
    if (!a.quiet) std::cerr << "wrote " << a.out << " (" << w << "x" << h << "x" << c << ")\n";
    return 0;
}

int run_decode(const VaeArgs& a) {
    Image lat = read_image(a.input);
    auto vae = pipeline::open_vae(a.vae);
    if (lat.channels != vae->convention().channels)
        throw std::runtime_error(a.input + ": " + std::to_string(lat.channels) + " channels, the VAE's latents have " +
                                 std::to_string(vae->convention().channels));
    std::vector<float> rgb = vae->decode(lat.data, lat.width, lat.height);
    // Decoded values are display-referred (about [0, 1]): EXR keeps them unclamped, PNG as they are.
    const int f = vae->convention().downsample;
    Image out{lat.width * f, lat.height * f, 3, rgb, {"R", "G", "B"}, true};
    if (fs::path(a.out).extension() == ".exr") write_exr(a.out, out);
    else write_png_display(a.out, out);
    if (!a.quiet) std::cerr << "wrote " << a.out << " (" << out.width << "x" << out.height << ")\n";
    return 0;
}

}  // namespace lpt::app
