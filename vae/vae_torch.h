// Differentiable entry points of a Vae, for losses through the decoder (the refiner's LPIPS).
// Include this ONLY from .cpp files that already compile against libtorch; torch-free callers
// use vae/vae.h. Tensors are NCHW float32: images in [0, 1], latents in the model's convention.
#pragma once
#include "vae/vae.h"
#include <torch/torch.h>

namespace lpt {

class TorchVae {
public:
    virtual ~TorchVae() = default;
    /// [N, 3, H, W] in [0, 1] → [N, C, H/f, W/f]. Differentiable.
    virtual torch::Tensor encode_nchw(const torch::Tensor& rgb) const = 0;
    /// [N, C, h, w] → [N, 3, f·h, f·w], about [0, 1], not clamped. Differentiable.
    virtual torch::Tensor decode_nchw(const torch::Tensor& latent) const = 0;
};

/// The differentiable side of `vae`, or nullptr if its implementation has none.
inline const TorchVae* torch_vae(const Vae& vae) { return dynamic_cast<const TorchVae*>(&vae); }

}  // namespace lpt
