// U-Net body of the refiner (docs/refiner.md "U-Net").
#include "refiner/refiner_unet_torch.h"
#include <stdexcept>

namespace lpt {

namespace {

constexpr int64_t kScale = 4;  // two 2× poolings

torch::nn::Conv2d conv3(int64_t in, int64_t out) {
    return torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, 3).padding(1));
}

torch::Tensor upsample2(const torch::Tensor& x) {
    return torch::nn::functional::interpolate(x, torch::nn::functional::InterpolateFuncOptions()
                                                     .scale_factor(std::vector<double>{2.0, 2.0})
                                                     .mode(torch::kNearest));
}

}  // namespace

UNetBlockImpl::UNetBlockImpl(int64_t in, int64_t out, bool instance_norm, float dropout) {
    a = register_module("a", conv3(in, out));
    b = register_module("b", conv3(out, out));
    if (instance_norm) {
        auto opts = torch::nn::InstanceNorm2dOptions(out).affine(true);
        na = register_module("na", torch::nn::InstanceNorm2d(opts));
        nb = register_module("nb", torch::nn::InstanceNorm2d(opts));
    }
    drop = register_module("drop", torch::nn::Dropout(torch::nn::DropoutOptions(dropout)));
}

torch::Tensor UNetBlockImpl::forward(const torch::Tensor& x) {
    auto norm = [](torch::nn::InstanceNorm2d& n, const torch::Tensor& t) { return n.is_empty() ? t : n(t); };
    torch::Tensor h = torch::relu(norm(na, a(x)));
    return drop(torch::relu(norm(nb, b(h))));
}

UNetBodyImpl::UNetBodyImpl(int64_t in, int64_t width, bool instance_norm, float dropout) {
    if (width < kScale || width % kScale != 0)
        throw std::invalid_argument("refiner: the U-Net needs a hidden width divisible by 4");
    const int64_t w1 = width / 4, w2 = width / 2;
    out = w1;
    enc1 = register_module("enc1", UNetBlock(in, w1, instance_norm, dropout));
    enc2 = register_module("enc2", UNetBlock(w1, w2, instance_norm, dropout));
    mid = register_module("mid", UNetBlock(w2, width, instance_norm, dropout));
    dec2 = register_module("dec2", UNetBlock(width + w2, w2, instance_norm, dropout));
    dec1 = register_module("dec1", UNetBlock(w2 + w1, w1, instance_norm, dropout));
}

torch::Tensor UNetBodyImpl::forward(const torch::Tensor& x) {
    namespace F = torch::nn::functional;
    const int64_t h = x.size(2), w = x.size(3);
    const int64_t ph = (kScale - h % kScale) % kScale, pw = (kScale - w % kScale) % kScale;
    // Replication, not zeros: the padded rows continue the view instead of adding an edge.
    const torch::Tensor xp = ph || pw ? F::pad(x, F::PadFuncOptions({0, pw, 0, ph}).mode(torch::kReplicate)) : x;
    const torch::Tensor s1 = enc1(xp);
    const torch::Tensor s2 = enc2(F::avg_pool2d(s1, F::AvgPool2dFuncOptions(2)));
    const torch::Tensor m = mid(F::avg_pool2d(s2, F::AvgPool2dFuncOptions(2)));
    const torch::Tensor d2 = dec2(torch::cat({upsample2(m), s2}, 1));
    const torch::Tensor d1 = dec1(torch::cat({upsample2(d2), s1}, 1));
    return ph || pw ? d1.narrow(2, 0, h).narrow(3, 0, w) : d1;
}

}  // namespace lpt
