// LPIPS v0.1, SqueezeNet-1.1 backbone, in libtorch, built from ../shared/models/lpips/FACTS.md:
// torchvision SqueezeNet 1.1 `features` (conv 3x3 s2 p0, max-pools 3x3 s2 ceil_mode, Fire
// modules with the 1x1 expand branch first), 7 taps after the ReLUs, per-pixel channel
// unit-normalisation f / (||f|| + 1e-10), squared difference, 1x1 linear heads without bias,
// spatial mean, sum over layers. Weights come from one safetensors file read by our reader.
#include "vae/lpips_torch.h"
#include "vae/safetensors.h"
#include "vae/torch_threads.h"
#include <algorithm>
#include <stdexcept>

namespace lpt {

namespace {

const char* kFile = "lpips_squeeze_v0.1.safetensors";
constexpr int64_t kTapChannels[Lpips::kLayers] = {64, 128, 256, 384, 384, 512, 512};

struct FireSpec {
    int idx;
    int64_t in, squeeze, expand;
};
// features.{3,4,6,7,9,10,11,12}: Fire(in -> squeeze -> expand + expand)
constexpr FireSpec kFires[] = {{3, 64, 16, 64},   {4, 128, 16, 64},   {6, 128, 32, 128},  {7, 256, 32, 128},
                               {9, 256, 48, 192}, {10, 384, 48, 192}, {11, 384, 64, 256}, {12, 512, 64, 256}};

using Expected = std::vector<std::pair<std::string, std::vector<int64_t>>>;

Expected expected_tensors() {
    Expected e;
    e.push_back({"features.0.weight", {64, 3, 3, 3}});
    e.push_back({"features.0.bias", {64}});
    for (const FireSpec& f : kFires) {
        const std::string p = "features." + std::to_string(f.idx) + ".";
        e.push_back({p + "squeeze.weight", {f.squeeze, f.in, 1, 1}});
        e.push_back({p + "squeeze.bias", {f.squeeze}});
        e.push_back({p + "expand1x1.weight", {f.expand, f.squeeze, 1, 1}});
        e.push_back({p + "expand1x1.bias", {f.expand}});
        e.push_back({p + "expand3x3.weight", {f.expand, f.squeeze, 3, 3}});
        e.push_back({p + "expand3x3.bias", {f.expand}});
    }
    for (int k = 0; k < Lpips::kLayers; ++k)
        e.push_back({"lin." + std::to_string(k) + ".weight", {1, kTapChannels[k], 1, 1}});
    e.push_back({"scaling.shift", {1, 3, 1, 1}});
    e.push_back({"scaling.scale", {1, 3, 1, 1}});
    return e;
}

/// The net's tensor in x's dtype and device (a no-op for float32 CPU inputs).
torch::Tensor like(const torch::Tensor& t, const torch::Tensor& x) {
    return (t.scalar_type() == x.scalar_type() && t.device() == x.device()) ? t : t.to(x.options());
}

torch::Tensor conv(const LpipsNet& n, const std::string& name, const torch::Tensor& x, int64_t stride,
                   int64_t padding) {
    return torch::conv2d(x, like(n.w.at(name + ".weight"), x), like(n.w.at(name + ".bias"), x), stride, padding);
}

torch::Tensor fire(const LpipsNet& n, int idx, const torch::Tensor& x) {
    const std::string p = "features." + std::to_string(idx) + ".";
    torch::Tensor s = torch::relu(conv(n, p + "squeeze", x, 1, 0));
    return torch::cat({torch::relu(conv(n, p + "expand1x1", s, 1, 0)), torch::relu(conv(n, p + "expand3x3", s, 1, 1))},
                      1);
}

torch::Tensor pool(const torch::Tensor& x) {
    if (x.size(2) < 2 || x.size(3) < 2)
        throw std::invalid_argument("LPIPS: the image is too small for the SqueezeNet backbone (needs at least " +
                                    std::to_string(Lpips::kMinSize) + "x" + std::to_string(Lpips::kMinSize) +
                                    " pixels)");
    return torch::max_pool2d(x, {3, 3}, {2, 2}, {0, 0}, {1, 1}, /*ceil_mode=*/true);
}

/// The 7 tap activations of the backbone for inputs already in [-1, 1].
std::array<torch::Tensor, Lpips::kLayers> taps(const LpipsNet& n, const torch::Tensor& x_in) {
    torch::Tensor x = (x_in - like(n.shift, x_in)) / like(n.scale, x_in);
    std::array<torch::Tensor, Lpips::kLayers> t;
    x = torch::relu(conv(n, "features.0", x, 2, 0));
    t[0] = x;
    x = pool(x);
    x = fire(n, 3, x);
    x = fire(n, 4, x);
    t[1] = x;
    x = pool(x);
    x = fire(n, 6, x);
    x = fire(n, 7, x);
    t[2] = x;
    x = pool(x);
    x = fire(n, 9, x);
    t[3] = x;
    x = fire(n, 10, x);
    t[4] = x;
    x = fire(n, 11, x);
    t[5] = x;
    x = fire(n, 12, x);
    t[6] = x;
    return t;
}

/// f / (sqrt(sum_c f^2) + 1e-10). The square root is taken through a guarded branch so that a
/// pixel whose features are all zero (ReLU) has a zero gradient instead of 0 * inf = NaN; the
/// forward value is exactly the official one.
torch::Tensor unit_normalise(const torch::Tensor& f) {
    torch::Tensor s = (f * f).sum(1, /*keepdim=*/true);
    torch::Tensor pos = s > 0;
    torch::Tensor norm =
        torch::where(pos, torch::sqrt(torch::where(pos, s, torch::ones_like(s))), torch::zeros_like(s));
    return f / (norm + 1e-10);
}

void check_inputs(const torch::Tensor& a, const torch::Tensor& b) {
    if (a.dim() != 4 || a.size(1) != 3 || a.sizes() != b.sizes())
        throw std::invalid_argument("lpips_torch: expects two NCHW RGB tensors of the same shape, got " +
                                    c10::str(a.sizes()) + " and " + c10::str(b.sizes()));
    if (a.size(2) < Lpips::kMinSize || a.size(3) < Lpips::kMinSize)
        throw std::invalid_argument("LPIPS: image " + std::to_string(a.size(3)) + "x" + std::to_string(a.size(2)) +
                                    " is too small for the SqueezeNet backbone (needs at least " +
                                    std::to_string(Lpips::kMinSize) + "x" + std::to_string(Lpips::kMinSize) + ")");
}

/// Interleaved RGB in [0, 1] -> NCHW in [-1, 1].
torch::Tensor to_nchw(const std::vector<float>& rgb, int width, int height, const char* which) {
    if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * height * 3)
        throw std::invalid_argument(std::string("LPIPS: image ") + which + " has " + std::to_string(rgb.size()) +
                                    " floats, expected " + std::to_string(width) + "x" + std::to_string(height) + "x3");
    return torch::from_blob(const_cast<float*>(rgb.data()), {1, height, width, 3}).permute({0, 3, 1, 2}) * 2.0 - 1.0;
}

}  // namespace

LpipsNet load_lpips_net(const std::string& dir) {
    LpipsNet n;
    n.path = dir + "/" + kFile;
    SafeTensors st = SafeTensors::load(n.path);
    const Expected expected = expected_tensors();
    for (const auto& [key, shape] : expected) {
        if (!st.has(key)) throw std::runtime_error(n.path + ": missing tensor '" + key + "'");
        std::vector<float> v = st.to_float(key, shape);
        n.w[key] = torch::from_blob(v.data(), shape, torch::kFloat32).clone();
    }
    if (st.tensors().size() != expected.size())
        throw std::runtime_error(n.path + ": " + std::to_string(st.tensors().size()) + " tensors, expected " +
                                 std::to_string(expected.size()) + " (not the LPIPS-squeeze v0.1 file?)");
    n.shift = n.w.at("scaling.shift");
    n.scale = n.w.at("scaling.scale");
    for (int k = 0; k < Lpips::kLayers; ++k) n.lin[k] = n.w.at("lin." + std::to_string(k) + ".weight");
    // Intra-op threads default to 1 here; convolutions dominate, so use the worker threads.
    use_worker_threads_in_torch();
    return n;
}

torch::Tensor lpips_torch_layers(const LpipsNet& net, const torch::Tensor& a, const torch::Tensor& b) {
    check_inputs(a, b);
    // Each input goes through the backbone on its own: identical inputs then give bitwise
    // identical features (distance exactly 0) and d(a, b) == d(b, a) exactly.
    const auto ta = taps(net, a), tb = taps(net, b);
    std::vector<torch::Tensor> per_layer;
    for (int k = 0; k < Lpips::kLayers; ++k) {
        torch::Tensor d = (unit_normalise(ta[k]) - unit_normalise(tb[k])).pow(2);
        torch::Tensor m = torch::conv2d(d, like(net.lin[k], d));  // [N, 1, H, W]
        per_layer.push_back(m.mean({1, 2, 3}));
    }
    return torch::stack(per_layer, 1);
}

torch::Tensor lpips_torch(const LpipsNet& net, const torch::Tensor& a, const torch::Tensor& b) {
    return lpips_torch_layers(net, a, b).sum(1);
}

Lpips::Lpips(std::unique_ptr<LpipsNet> net) : m_net(std::move(net)) {}
Lpips::~Lpips() = default;

std::unique_ptr<Lpips> Lpips::load(const std::string& dir) {
    return std::unique_ptr<Lpips>(new Lpips(std::make_unique<LpipsNet>(load_lpips_net(dir))));
}

const std::string& Lpips::path() const { return m_net->path; }

std::vector<double> Lpips::layer_distances(const std::vector<float>& rgb_a, const std::vector<float>& rgb_b, int width,
                                           int height) const {
    torch::NoGradGuard no_grad;
    torch::Tensor l =
        lpips_torch_layers(*m_net, to_nchw(rgb_a, width, height, "a"), to_nchw(rgb_b, width, height, "b"));
    std::vector<double> out(kLayers);
    for (int k = 0; k < kLayers; ++k) out[k] = l[0][k].item<double>();
    return out;
}

double Lpips::distance(const std::vector<float>& rgb_a, const std::vector<float>& rgb_b, int width, int height) const {
    torch::NoGradGuard no_grad;
    return lpips_torch(*m_net, to_nchw(rgb_a, width, height, "a"), to_nchw(rgb_b, width, height, "b"))[0]
        .item<double>();
}

}  // namespace lpt
