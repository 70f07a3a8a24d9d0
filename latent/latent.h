// The latent space the renderer works in: the SD3 / SD3.5 VAE's 16 channels. Everything that
// depends on that width (the latent model, the adjoints, the fit, the refiner's inputs) reads it
// from here.
#pragma once
#include "core/spectrum.h"

namespace lpt {

constexpr int kLatentChannels = 16;
using Latent = Spectrum<kLatentChannels>;

}  // namespace lpt
