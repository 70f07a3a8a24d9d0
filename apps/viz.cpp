// `latentpt viz`: a picture of a latent's channels (no VAE, so no libtorch).
#include "apps/commands.h"
#include "core/image_io.h"
#include "core/latent_viz.h"
#include <iostream>

namespace lpt::app {

int run_viz(const VaeArgs& a) {
    Image lat = read_image(a.input);
    require_finite_pixels(lat, a.input);  // a NaN channel drew as zero
    write_png_srgb(a.out, latent_grid(lat.data.data(), lat.width, lat.height, lat.channels));
    if (!a.quiet) std::cerr << "wrote " << a.out << "\n";
    return 0;
}

}  // namespace lpt::app
