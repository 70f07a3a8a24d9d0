// The refiner's libtorch network, shared by refiner_net.cpp (build, apply, save, load) and
// refiner_train.cpp. Internal to refiner/: include only from .cpp files there.
#pragma once
#include "refiner/refiner.h"
#include "refiner/refiner_unet_torch.h"
#include <torch/torch.h>

namespace lpt {

/// tanh(x / squash) → body → 1×1 conv, and the result is added to the unsquashed latent (the
/// first latent_channels input channels). The conv body: [conv k, InstanceNorm (unless
/// config.instance_norm is false), ReLU, Dropout] for k = 3, 5, 3; the unet body: UNetBody.
struct RefinerNetImpl : torch::nn::Module {
    explicit RefinerNetImpl(const RefinerConfig& config);
    /// x: [N, refiner_input_channels, h, w] (latent, normal xyz, scaled distance[, Ĩe, Ĩa, Ĩc]) →
    /// refined latent. body_noise ([N, latent_channels, h, w], training only) is added to the
    /// latent the body reads, not to the one its output is added to (RefinerTrainOptions::input_noise).
    torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& body_noise = {});

    RefinerConfig cfg;
    torch::nn::Conv2d c1{nullptr}, c2{nullptr}, c3{nullptr}, head{nullptr};  ///< c1–c3: conv body only
    torch::nn::InstanceNorm2d n1{nullptr}, n2{nullptr}, n3{nullptr};         ///< empty without instance_norm
    torch::nn::Dropout drop{nullptr};
    UNetBody unet{nullptr};  ///< unet body only
};
TORCH_MODULE(RefinerNet);

struct Refiner::Impl {
    RefinerConfig config;
    RefinerNet net;
};

constexpr int kRefinerAovChannels = 4;  ///< normal (3) + distance (1)
/// Input channels of a network with `config`: latent, AOVs, with config.terms Ĩe, Ĩa, Ĩc, and
/// with config.emitter_cells the sub-cells' emitter coverage.
int64_t refiner_input_channels(const RefinerConfig& config);

/// The instance_norm flag stored in a refiner.pt or checkpoint archive; files written before the
/// option have none and all had InstanceNorm.
bool archived_instance_norm(torch::serialize::InputArchive& ar);
/// The body stored in a refiner.pt or checkpoint archive; files written before the option are conv.
RefinerArch archived_arch(torch::serialize::InputArchive& ar);
/// The terms flag stored in an archive; files written before the option read no terms.
bool archived_terms(torch::serialize::InputArchive& ar);
/// The emitter cells stored in an archive; files written before the option read 0.
int archived_emitter_cells(torch::serialize::InputArchive& ar);

/// The network input [1, refiner_input_channels, h, w] of a view (distance divided by
/// config.distance_scale; the terms appended when config.terms, then the emitter cells).
/// Throws std::invalid_argument on buffer sizes that do not match width × height.
torch::Tensor refiner_input_tensor(const RefinerInput& in, const RefinerConfig& config);
/// [1, C, h, w] → interleaved h × w × C floats.
std::vector<float> refiner_to_hwc(const torch::Tensor& nchw);

}  // namespace lpt
