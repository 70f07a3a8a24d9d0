// Refiner network: construction, inference, and the refiner.pt file (a torch::serialize
// archive holding the weights and the RefinerConfig, written atomically).
#include "refiner/refiner_net.h"
#include "core/temp_file.h"
#include "vae/torch_threads.h"
#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <utility>
#include <vector>

namespace lpt {

namespace {

torch::nn::Conv2d conv(int64_t in, int64_t out, int64_t k) {
    return torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, k).padding(k / 2));
}

/// Origins of windows of `window` pixels along an axis of `size`: every `stride` pixels, and the
/// last one flush with the far edge, so that every pixel is covered.
std::vector<int64_t> window_origins(int64_t size, int64_t window, int64_t stride) {
    std::vector<int64_t> origins;
    for (int64_t o = 0; o + window < size; o += stride) origins.push_back(o);
    origins.push_back(std::max<int64_t>(0, size - window));
    return origins;
}

/// The network on tile×tile windows of x (fewer pixels along an axis shorter than that) every
/// `stride` pixels, the outputs averaged where windows overlap. Windows go through in batches to
/// bound memory; the sums run in a fixed order, so the result is deterministic.
torch::Tensor forward_in_windows(RefinerNet& net, const torch::Tensor& x, int tile, int stride) {
    constexpr size_t kBatch = 32;
    const int64_t h = x.size(2), w = x.size(3), th = std::min<int64_t>(tile, h), tw = std::min<int64_t>(tile, w);
    std::vector<std::pair<int64_t, int64_t>> windows;
    for (int64_t y : window_origins(h, th, std::min<int64_t>(stride, th)))  // a longer step would skip pixels
        for (int64_t x0 : window_origins(w, tw, std::min<int64_t>(stride, tw))) windows.emplace_back(y, x0);
    torch::Tensor sum = torch::zeros({1, int64_t(net->cfg.latent_channels), h, w});
    torch::Tensor count = torch::zeros({1, 1, h, w});
    for (size_t first = 0; first < windows.size(); first += kBatch) {
        const size_t n = std::min(kBatch, windows.size() - first);
        std::vector<torch::Tensor> crops;
        for (size_t i = first; i < first + n; ++i)
            crops.push_back(x.narrow(2, windows[i].first, th).narrow(3, windows[i].second, tw));
        const torch::Tensor out = net->forward(torch::cat(crops, 0));
        for (size_t i = 0; i < n; ++i) {
            const auto [y, x0] = windows[first + i];
            sum.narrow(2, y, th).narrow(3, x0, tw).add_(out.narrow(0, int64_t(i), 1));
            count.narrow(2, y, th).narrow(3, x0, tw).add_(1.0);
        }
    }
    return sum / count;
}

/// x with `noise` added to its first `channels` channels (the latent); x itself when undefined.
torch::Tensor with_latent_noise(const torch::Tensor& x, const torch::Tensor& noise, int64_t channels) {
    if (!noise.defined()) return x;
    return torch::cat({x.narrow(1, 0, channels) + noise, x.narrow(1, channels, x.size(1) - channels)}, 1);
}

}  // namespace

RefinerNetImpl::RefinerNetImpl(const RefinerConfig& config) : cfg(config) {
    if (config.latent_channels < 1 || config.expansion < 1 || !(config.squash > 0.f) ||
        !(config.dropout >= 0.f && config.dropout < 1.f) || !(config.distance_scale > 0.f))
        throw std::invalid_argument(
            "refiner: invalid configuration (channels, expansion >= 1; squash, distance scale > 0; dropout in [0, 1))");
    const int64_t c = config.latent_channels, width = int64_t(config.expansion) * c;
    if (config.arch == RefinerArch::UNet) {
        unet = register_module("unet",
                               UNetBody(refiner_input_channels(config), width, config.instance_norm, config.dropout));
        head = register_module("head", conv(unet->out_channels(), c, 1));
        return;
    }
    c1 = register_module("c1", conv(refiner_input_channels(config), width, 3));
    c2 = register_module("c2", conv(width, width, 5));
    c3 = register_module("c3", conv(width, width, 3));
    head = register_module("head", conv(width, c, 1));
    auto norm = [&](const char* name) {
        return register_module(name, torch::nn::InstanceNorm2d(torch::nn::InstanceNorm2dOptions(width).affine(true)));
    };
    if (config.instance_norm) {
        n1 = norm("n1");
        n2 = norm("n2");
        n3 = norm("n3");
    }
    drop = register_module("drop", torch::nn::Dropout(torch::nn::DropoutOptions(config.dropout)));
}

torch::Tensor RefinerNetImpl::forward(const torch::Tensor& x, const torch::Tensor& body_noise) {
    auto norm = [](torch::nn::InstanceNorm2d& n, const torch::Tensor& t) { return n.is_empty() ? t : n(t); };
    torch::Tensor h = torch::tanh(with_latent_noise(x, body_noise, cfg.latent_channels) / cfg.squash);
    if (!unet.is_empty()) return x.narrow(1, 0, cfg.latent_channels) + head(unet(h));
    h = drop(torch::relu(norm(n1, c1(h))));
    h = drop(torch::relu(norm(n2, c2(h))));
    h = drop(torch::relu(norm(n3, c3(h))));
    return x.narrow(1, 0, cfg.latent_channels) + head(h);
}

bool archived_instance_norm(torch::serialize::InputArchive& ar) {
    c10::IValue norm;
    return !ar.try_read("config.instance_norm", norm) || norm.toInt() != 0;
}

RefinerArch archived_arch(torch::serialize::InputArchive& ar) {
    c10::IValue arch;
    return ar.try_read("config.arch", arch) && arch.toInt() == int64_t(RefinerArch::UNet) ? RefinerArch::UNet
                                                                                          : RefinerArch::Conv;
}

bool archived_terms(torch::serialize::InputArchive& ar) {
    c10::IValue terms;
    return ar.try_read("config.terms", terms) && terms.toInt() != 0;
}

int archived_emitter_cells(torch::serialize::InputArchive& ar) {
    c10::IValue cells;
    return ar.try_read("config.emitter_cells", cells) ? int(cells.toInt()) : 0;
}

int64_t refiner_input_channels(const RefinerConfig& config) {
    return int64_t(config.latent_channels) * (config.terms ? 4 : 1) + kRefinerAovChannels +
           emitter_cell_channels(config);
}

torch::Tensor refiner_input_tensor(const RefinerInput& in, const RefinerConfig& config) {
    const int64_t w = in.width, h = in.height, c = config.latent_channels, n = w * h;
    if (w < 1 || h < 1) throw std::invalid_argument("refiner: empty view");
    if (int64_t(in.latent.size()) != n * c || int64_t(in.normal.size()) != n * 3 || int64_t(in.distance.size()) != n)
        throw std::invalid_argument("refiner: a " + std::to_string(w) + "x" + std::to_string(h) + " view needs " +
                                    std::to_string(c) + " latent, 3 normal and 1 distance channels per pixel");
    if (config.terms && int64_t(in.terms.size()) != n * 3 * c)
        throw std::invalid_argument("refiner: this refiner reads the transport terms: a " + std::to_string(w) + "x" +
                                    std::to_string(h) + " view needs " + std::to_string(3 * c) +
                                    " term channels per pixel (Ĩe, Ĩa, Ĩc), got " + std::to_string(in.terms.size()) +
                                    " values");
    const int64_t cells = emitter_cell_channels(config);
    if (cells && int64_t(in.emitter.size()) != n * cells)
        throw std::invalid_argument("refiner: this refiner reads emitter cells: a " + std::to_string(w) + "x" +
                                    std::to_string(h) + " view needs " + std::to_string(cells) +
                                    " emitter coverage channels per pixel, got " + std::to_string(in.emitter.size()) +
                                    " values");
    auto nchw = [&](const std::vector<float>& v, int64_t ch) {
        return torch::from_blob(const_cast<float*>(v.data()), {1, h, w, ch}).permute({0, 3, 1, 2});
    };
    std::vector<torch::Tensor> parts = {nchw(in.latent, c), nchw(in.normal, 3),
                                        nchw(in.distance, 1) / config.distance_scale};
    if (config.terms) parts.push_back(nchw(in.terms, 3 * c));
    if (cells) parts.push_back(nchw(in.emitter, cells));
    return torch::cat(parts, 1).contiguous();
}

std::vector<float> refiner_to_hwc(const torch::Tensor& nchw) {
    torch::Tensor t = nchw.permute({0, 2, 3, 1}).contiguous();
    return std::vector<float>(t.data_ptr<float>(), t.data_ptr<float>() + t.numel());
}

Refiner::Refiner(std::unique_ptr<Impl> impl) : m(std::move(impl)) {}
Refiner::~Refiner() = default;

std::unique_ptr<Refiner> Refiner::create(const RefinerConfig& config, uint64_t seed) {
    use_worker_threads_in_torch();
    torch::manual_seed(seed);
    auto impl = std::make_unique<Impl>(Impl{config, RefinerNet(config)});
    // A zero head makes the untrained refiner the identity: stage 2 starts from stage 1's result.
    torch::NoGradGuard no_grad;
    impl->net->head->weight.zero_();
    impl->net->head->bias.zero_();
    return std::unique_ptr<Refiner>(new Refiner(std::move(impl)));
}

const RefinerConfig& Refiner::config() const { return m->config; }

int64_t Refiner::parameter_count() const {
    int64_t n = 0;
    for (const auto& p : m->net->parameters()) n += p.numel();
    return n;
}

std::vector<float> Refiner::refine(const RefinerInput& input) const {
    torch::NoGradGuard no_grad;
    m->net->eval();
    const torch::Tensor x = refiner_input_tensor(input, m->config);
    const int tile = m->config.tile;
    const bool one_window = tile <= 0 || (input.width <= tile && input.height <= tile);
    if (one_window) return refiner_to_hwc(m->net->forward(x));
    return refiner_to_hwc(forward_in_windows(m->net, x, tile, inference_stride(m->config)));
}

void Refiner::save(const std::string& path) const {
    torch::serialize::OutputArchive ar;
    m->net->save(ar);
    const RefinerConfig& c = m->config;
    ar.write("config.latent_channels", c10::IValue(int64_t(c.latent_channels)));
    ar.write("config.expansion", c10::IValue(int64_t(c.expansion)));
    ar.write("config.squash", c10::IValue(double(c.squash)));
    ar.write("config.dropout", c10::IValue(double(c.dropout)));
    ar.write("config.distance_scale", c10::IValue(double(c.distance_scale)));
    ar.write("config.instance_norm", c10::IValue(int64_t(c.instance_norm)));
    ar.write("config.tile", c10::IValue(int64_t(c.tile)));
    if (c.window_stride > 0) ar.write("config.window_stride", c10::IValue(int64_t(c.window_stride)));  // else as before
    if (c.arch != RefinerArch::Conv) ar.write("config.arch", c10::IValue(int64_t(c.arch)));  // conv files as before
    if (c.terms) ar.write("config.terms", c10::IValue(int64_t(1)));  // files without terms as before
    if (c.emitter_cells) ar.write("config.emitter_cells", c10::IValue(int64_t(c.emitter_cells)));  // else as before
    const std::string tmp = path + ".tmp";
    const TemporaryFile removed_if_interrupted(tmp);  // Ctrl-C while saving leaves no .tmp
    ar.save_to(tmp);
    std::filesystem::rename(tmp, path);
}

std::unique_ptr<Refiner> Refiner::load(const std::string& path) {
    if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": refiner file not found");
    use_worker_threads_in_torch();
    try {
        torch::serialize::InputArchive ar;
        ar.load_from(path);
        auto get = [&](const char* key) {
            c10::IValue v;
            if (!ar.try_read(key, v))
                throw std::runtime_error(path + ": not a latentpt refiner (no '" + std::string(key) + "')");
            return v;
        };
        RefinerConfig c;
        c.latent_channels = int(get("config.latent_channels").toInt());
        c.expansion = int(get("config.expansion").toInt());
        c.squash = float(get("config.squash").toDouble());
        c.dropout = float(get("config.dropout").toDouble());
        c.distance_scale = float(get("config.distance_scale").toDouble());
        c.instance_norm = archived_instance_norm(ar);
        c10::IValue tile;
        c.tile = ar.try_read("config.tile", tile) ? int(tile.toInt()) : 0;  // older files: the whole view
        c10::IValue stride;
        c.window_stride = ar.try_read("config.window_stride", stride) ? int(stride.toInt()) : 0;  // older: tile / 2
        c.arch = archived_arch(ar);
        c.terms = archived_terms(ar);
        c.emitter_cells = archived_emitter_cells(ar);
        auto impl = std::make_unique<Impl>(Impl{c, RefinerNet(c)});
        impl->net->load(ar);
        return std::unique_ptr<Refiner>(new Refiner(std::move(impl)));
    } catch (const c10::Error& e) {
        throw std::runtime_error(path + ": cannot read refiner: " + e.what_without_backtrace());
    }
}

}  // namespace lpt
