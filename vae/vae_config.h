// vae.json: the conventions of a VAE exported as TorchScript modules (tools/export_vae.py):
//   {"channels": 16, "downsample": 8, "scale": 1.5305, "shift": 0.0609,
//    "image_range": [-1, 1], "latent": "raw" | "model"}
// Torch-free, so the sanitizer build fuzzes it (tests/fuzz/).
#pragma once
#include "vae/vae.h"
#include <string>

namespace lpt {

struct VaeConfig {
    LatentConvention convention;
    float image_lo = 0.f, image_hi = 1.f;  ///< the modules' image range
    bool raw_latent = false;               ///< modules speak raw latents: scale and shift applied here
};

/// Throws std::runtime_error naming the file and the field for anything missing or out of range.
VaeConfig read_vae_config(const std::string& path);
/// Same, from the file's text (`path` only labels errors).
VaeConfig parse_vae_config(const std::string& text, const std::string& path);

}  // namespace lpt
