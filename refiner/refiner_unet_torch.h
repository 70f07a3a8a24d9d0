// The refiner's U-Net body (`--refiner-arch unet`): two poolings and two upsamplings with skip
// connections, so a pixel's output sees ~44 latent pixels around it instead of the three-conv
// body's 9, at a fifth of its multiply-adds per pixel. Internal to refiner/.
#pragma once
#include <torch/torch.h>

namespace lpt {

/// Conv3×3 → [InstanceNorm] → ReLU, twice, then Dropout.
struct UNetBlockImpl : torch::nn::Module {
    UNetBlockImpl(int64_t in, int64_t out, bool instance_norm, float dropout);
    torch::Tensor forward(const torch::Tensor& x);

    torch::nn::Conv2d a{nullptr}, b{nullptr};
    torch::nn::InstanceNorm2d na{nullptr}, nb{nullptr};  ///< empty without InstanceNorm
    torch::nn::Dropout drop{nullptr};
};
TORCH_MODULE(UNetBlock);

/// in channels at h × w → `width` / 4 feature channels at h × w; widths width/4, width/2, width at
/// full, half and quarter resolution. Sizes that are not multiples of 4 are padded by replication
/// on the right and bottom and cropped again.
struct UNetBodyImpl : torch::nn::Module {
    UNetBodyImpl(int64_t in, int64_t width, bool instance_norm, float dropout);
    torch::Tensor forward(const torch::Tensor& x);
    int64_t out_channels() const { return out; }

    int64_t out = 0;
    UNetBlock enc1{nullptr}, enc2{nullptr}, mid{nullptr}, dec2{nullptr}, dec1{nullptr};
};
TORCH_MODULE(UNetBody);

}  // namespace lpt
