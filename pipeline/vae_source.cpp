#include "pipeline/vae_source.h"
#include "core/fingerprint.h"
#include "core/image_io.h"
#include "pipeline/paths.h"
#include "vae/vae.h"
#include <filesystem>
#include <stdexcept>

namespace lpt::pipeline {

namespace fs = std::filesystem;

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

std::string vae_encoder_fingerprint(const VaeSource& s) {
    Fingerprint fingerprint;
    if (s.torchscript()) {
        fingerprint.add(read_file(s.encoder));
        fingerprint.add(read_file(s.config));
    } else {
        fingerprint.add(read_file((fs::path(default_vae_dir(s.dir)) / "taesd3_encoder.safetensors").string()));
    }
    return "fnv1a64:" + fingerprint.hex();
}

}  // namespace lpt::pipeline
