// Differentiable libtorch cores of the image metrics (LPIPS, SSIM) for losses, e.g. the refiner.
// Include this ONLY from .cpp files that already include libtorch: it pulls in <torch/torch.h>.
// Torch-free callers use vae/lpips.h and vae/ssim.h. Nothing here disables autograd: gradients
// flow to the inputs (the LPIPS weights are constants without requires_grad).
#pragma once
#include "vae/lpips.h"
#include <torch/torch.h>
#include <array>
#include <map>
#include <string>

namespace lpt {

struct LpipsNet {
    std::string path;                               ///< the safetensors file
    std::map<std::string, torch::Tensor> w;         ///< backbone, torchvision names (features.N.*)
    torch::Tensor shift, scale;                     ///< scaling layer, [1, 3, 1, 1]
    std::array<torch::Tensor, Lpips::kLayers> lin;  ///< linear heads, [1, C_k, 1, 1], no bias
};

/// `<dir>/lpips_squeeze_v0.1.safetensors` as float32 CPU tensors (throws like Lpips::load).
LpipsNet load_lpips_net(const std::string& dir);

/// LPIPS v0.1 (SqueezeNet) between NCHW RGB batches `a`, `b` with values in [-1, 1] (the
/// scaling layer is applied inside). Returns the distance per batch element, shape [N].
/// Differentiable w.r.t. both inputs; any floating dtype (weights are cast to it).
torch::Tensor lpips_torch(const LpipsNet& net, const torch::Tensor& a, const torch::Tensor& b);
/// Same, per layer: shape [N, 7]; lpips_torch is its sum over dim 1.
torch::Tensor lpips_torch_layers(const LpipsNet& net, const torch::Tensor& a, const torch::Tensor& b);

/// SSIM as vae/ssim.h defines it (11x11 Gaussian window, sigma 1.5, 'valid' filtering,
/// C1 = (0.01 L)^2, C2 = (0.03 L)^2, mean over positions then channels) on NCHW batches with any
/// channel count. Returns [N]. Differentiable; computed in the inputs' dtype (use double to
/// match the plain-C++ ssim() to ~1e-12, float32 agrees to ~1e-6).
torch::Tensor ssim_torch(const torch::Tensor& a, const torch::Tensor& b, double data_range);

}  // namespace lpt
