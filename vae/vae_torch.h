// Differentiable entry points of a Vae, for losses through the decoder (the refiner's LPIPS).
// Include this ONLY from .cpp files that already compile against libtorch; torch-free callers
// use vae/vae.h. Tensors are NCHW float32: images in [0, 1], latents in the model's convention.
#pragma once
#include "vae/vae.h"
#include <torch/torch.h>
#include <stdexcept>
#include <string>
#include <vector>

namespace lpt {

class TorchVae {
public:
    virtual ~TorchVae() = default;
    /// [N, 3, H, W] in [0, 1] → [N, C, H/f, W/f]. Differentiable.
    virtual torch::Tensor encode_nchw(const torch::Tensor& rgb) const = 0;
    /// [N, C, h, w] → [N, 3, f·h, f·w], about [0, 1], not clamped. Differentiable.
    virtual torch::Tensor decode_nchw(const torch::Tensor& latent) const = 0;
};

/// A Vae whose buffer API is its NCHW one: size checks, HWC <-> NCHW and no-grad are here once.
/// Implementations provide encode_nchw / decode_nchw and convention().
class NchwVae : public Vae, public TorchVae {
public:
    std::vector<float> encode(const std::vector<float>& rgb, int width, int height) const final {
        const int f = convention().downsample;
        if (width % f || height % f)
            throw std::invalid_argument("encode: image " + std::to_string(width) + "x" + std::to_string(height) +
                                        " is not a multiple of " + std::to_string(f) +
                                        " in both axes (crop or pad it first)");
        if (rgb.size() != size_t(width) * height * 3)
            throw std::invalid_argument("encode: expected width*height*3 floats");
        torch::NoGradGuard no_grad;
        return to_hwc(encode_nchw(torch::from_blob(const_cast<float*>(rgb.data()), {1, height, width, 3})
                                      .permute({0, 3, 1, 2})
                                      .contiguous()));
    }
    std::vector<float> decode(const std::vector<float>& latent, int width, int height) const final {
        const int c = convention().channels;
        if (latent.size() != size_t(width) * height * c)
            throw std::invalid_argument("decode: expected " + std::to_string(width) + "x" + std::to_string(height) +
                                        "x" + std::to_string(c) + " floats, got " + std::to_string(latent.size()));
        torch::NoGradGuard no_grad;
        return to_hwc(decode_nchw(torch::from_blob(const_cast<float*>(latent.data()), {1, height, width, c})
                                      .permute({0, 3, 1, 2})
                                      .contiguous()));
    }

private:
    static std::vector<float> to_hwc(const torch::Tensor& nchw) {
        torch::Tensor t = nchw.permute({0, 2, 3, 1}).contiguous().to(torch::kFloat32);
        return std::vector<float>(t.data_ptr<float>(), t.data_ptr<float>() + t.numel());
    }
};

/// The differentiable side of `vae`, or nullptr if its implementation has none.
inline const TorchVae* torch_vae(const Vae& vae) { return dynamic_cast<const TorchVae*>(&vae); }

}  // namespace lpt
