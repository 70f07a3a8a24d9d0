// `latentpt encode | decode`: images to latents and back through the VAE (libtorch stays in
// vae/; this file is part of the torch plugin, apps/torch_commands.h).
#include "apps/commands.h"
#include "core/image_io.h"
#include "pipeline/reference.h"
#include "pipeline/vae_source.h"
#include "vae/vae.h"
#include <filesystem>
#include <iostream>

namespace lpt::app {

namespace fs = std::filesystem;

namespace {

void require_rgb(const Image& img, const std::string& path) {
    if (img.channels != 3 && img.channels != 4)  // a 16-channel latent encoded its first three
        throw std::runtime_error(path + ": needs 3 channels (RGB) or 4 (RGBA), has " + std::to_string(img.channels));
}

}  // namespace

int run_encode(const VaeArgs& a) {
    Image img = read_image(a.input);
    require_finite_pixels(img, a.input);  // the encoder spreads one NaN over its whole receptive field
    auto vae = pipeline::open_vae(a.vae);
    // TAESD wants display values; a linear EXR is mapped as fit maps its references, so that a
    // render's encoding here is the latent fit --encode would target.
    require_rgb(img, a.input);
    const std::vector<float> rgb = pipeline::display_rgb(img, a.input);
    std::vector<float> latent = vae->encode(rgb, img.width, img.height);
    const int c = vae->convention().channels, w = img.width / vae->convention().downsample,
              h = img.height / vae->convention().downsample;
    write_exr(a.out, Image{w, h, c, latent, {}});
    if (!a.quiet) std::cerr << "wrote " << a.out << " (" << w << "x" << h << "x" << c << ")\n";
    return 0;
}

int run_decode(const VaeArgs& a) {
    Image lat = read_image(a.input);
    require_finite_pixels(lat, a.input);
    auto vae = pipeline::open_vae(a.vae);
    if (lat.channels != vae->convention().channels)
        throw std::runtime_error(a.input + ": " + std::to_string(lat.channels) + " channels, the VAE's latents have " +
                                 std::to_string(vae->convention().channels));
    std::vector<float> rgb = vae->decode(lat.data, lat.width, lat.height);
    // Decoded values are display-referred (about [0, 1]): EXR keeps them unclamped, PNG as they are.
    const int f = vae->convention().downsample;
    Image out{lat.width * f, lat.height * f, 3, rgb, {"R", "G", "B"}, true};
    const std::string ext = lower_extension(a.out);
    if (ext != ".exr" && ext != ".png")  // "d.jpg" got PNG bytes, "d.EXR" too
        throw std::invalid_argument(a.out + ": --out must end in .png or .exr");
    if (ext == ".exr") write_exr(a.out, out);
    else write_png_display(a.out, out);
    if (!a.quiet) std::cerr << "wrote " << a.out << " (" << out.width << "x" << out.height << ")\n";
    return 0;
}

}  // namespace lpt::app
