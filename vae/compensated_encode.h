// A latent target whose decoding matches the image better than its plain encoding does.
// The VAE's round trip x → dec(enc(x)) loses detail the latents cannot carry, and also shifts
// colours over whole regions (TAESD3 on the Cornell box: mean blue −0.009), a low-frequency
// error the latents can carry. Encoding x with that part of the round trip's residual added,
//   t′ = enc(x + lowpass(x − dec(enc(x)))),  lowpass = the mean over each latent cell's pixels,
// gives a target that decodes closer to x (docs/refiner.md "Latent target"). Torch-free: it only
// calls the Vae interface.
#pragma once
#include "vae/vae.h"
#include <vector>

namespace lpt {

/// Each f × f block of a width × height × channels image replaced by its mean (width, height
/// multiples of f).
std::vector<float> block_mean(const std::vector<float>& image, int width, int height, int channels, int f);

/// t′ above for an RGB image in [0, 1] (width × height × 3, multiples of the VAE's downsample
/// factor); lowpass over blocks of `block` pixels (0: that factor, one block per latent pixel;
/// coarser blocks keep only a broader cast of the round trip, see docs/refiner.md).
std::vector<float> encode_compensated(const Vae& vae, const std::vector<float>& rgb, int width, int height,
                                      int block = 0);

}  // namespace lpt
