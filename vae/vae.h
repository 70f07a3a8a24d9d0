// Image autoencoder interface, torch-free: images and latents are plain float buffers,
// interleaved per pixel (row-major from the top-left), like our films. Implementations hide
// libtorch (taesd.cpp). Latents are in the diffusion model's space (the VAE's raw latent scaled
// and shifted, `convention`), which is what TAESD3 reads and writes directly.
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace lpt {

struct LatentConvention {
    int channels = 16;
    int downsample = 8;     ///< image pixels per latent pixel, per axis
    float scale = 1.5305f;  ///< model latent = (raw VAE latent − shift) · scale
    float shift = 0.0609f;
};

class Vae {
public:
    virtual ~Vae() = default;
    /// RGB in [0, 1] (width × height × 3) → latent (width/8 × height/8 × channels). Sizes that
    /// are not multiples of `downsample` are rejected with a message (no silent padding).
    virtual std::vector<float> encode(const std::vector<float>& rgb, int width, int height) const = 0;
    /// Latent (w × h × channels) → RGB (8w × 8h × 3), approximately [0, 1], not clamped.
    virtual std::vector<float> decode(const std::vector<float>& latent, int width, int height) const = 0;
    virtual const LatentConvention& convention() const = 0;
};

/// TAESD-family network (TAESD3 by default) from `<dir>/<prefix>_encoder.safetensors` and
/// `_decoder.safetensors`; throws std::runtime_error naming the file on a missing file, a
/// missing tensor or a shape mismatch.
std::unique_ptr<Vae> load_taesd(const std::string& dir, const std::string& prefix = "taesd3",
                                const LatentConvention& convention = LatentConvention{});

/// A VAE exported as TorchScript: `encoder` and `decoder` modules and `config` (vae.json: channels,
/// downsample, scale, shift, image_range, latent "raw" | "model"; docs/vae.md). Throws
/// std::runtime_error naming the file and field on a missing file, a bad module or config.
std::unique_ptr<Vae> load_torchscript_vae(const std::string& encoder, const std::string& decoder,
                                          const std::string& config);

}  // namespace lpt
