// Which autoencoder a command uses: TAESD3 weights in a folder (native), or a TorchScript export
// (encoder, decoder and vae.json; tools/export_vae.py makes them for the SD3.5 VAE).
#pragma once
#include <memory>
#include <string>

namespace lpt {
class Vae;
}

namespace lpt::pipeline {

struct VaeSource {
    std::string dir;                       ///< empty = ../shared/models/taesd3 (LATENTPT_SHARED overrides)
    std::string encoder, decoder, config;  ///< TorchScript modules and vae.json
    bool torchscript() const { return !encoder.empty() || !decoder.empty() || !config.empty(); }
};

/// Loads the VAE; throws with the file name if it is missing or broken, or if only part of the
/// TorchScript triple is given.
std::unique_ptr<Vae> open_vae(const VaeSource& source);
/// Whether open_vae can be expected to find its files (for "no VAE: latents only" fallbacks).
bool vae_present(const VaeSource& source);
/// A fingerprint of what makes the VAE's encodings what they are: its encoder's weights (and a
/// TorchScript VAE's vae.json, whose scale and shift it applies), by content, not by path. Cached
/// latents and fit checkpoints record it, so that another VAE's are never taken for this one's.
std::string vae_encoder_fingerprint(const VaeSource& source);

}  // namespace lpt::pipeline
