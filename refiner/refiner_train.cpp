// Refiner training (stage 2): Adam on MSE + (1 − SSIM) of latents plus LPIPS of decoded crops,
// on random crops of the training examples (the training view, and renders or augmented copies of
// it) so an iteration stays cheap on a CPU. Example, crop positions, dropout masks and input
// noise are functions of (seed, iteration), so a resumed run repeats the same iterations as an
// uninterrupted one.
#include "autodiff/lr_schedule.h"
#include "core/temp_file.h"
#include "core/sampler.h"
#include "refiner/refiner_net.h"
#include "vae/lpips_torch.h"
#include "vae/ssim.h"
#include "vae/vae_torch.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace lpt {

namespace {

/// splitmix64: the golden-ratio step, then the shared finaliser (core/sampler.h).
uint64_t mix(uint64_t x) { return mix64(x + 0x9e3779b97f4a7c15ull); }

int pick(uint64_t key, int range) { return range <= 0 ? 0 : int(mix(key) % uint64_t(range + 1)); }

using ParamCopy = std::vector<torch::Tensor>;

ParamCopy copy_params(torch::nn::Module& net) {
    ParamCopy c;
    for (const auto& p : net.parameters()) c.push_back(p.detach().clone());
    return c;
}

void put_params(torch::nn::Module& net, const ParamCopy& c) {
    torch::NoGradGuard no_grad;
    auto ps = net.parameters();
    for (size_t i = 0; i < ps.size(); ++i) ps[i].copy_(c[i]);
}

constexpr double kSmoothing = 0.98;  // EMA of the crop loss: crops differ, the smoothed loss decides

/// Everything a training run carries from one iteration to the next, and its checkpoint.
struct TrainingState {
    torch::optim::Adam adam;
    RefinerTrainResult result;
    EarlyStopping stop;
    ParamCopy best;
    int start = 0;
    double smoothed = 0;

    TrainingState(RefinerNet& net, const RefinerTrainOptions& o)
        : adam(net->parameters(), torch::optim::AdamOptions(o.lr)),
          stop(std::max(1, o.patience), o.min_delta),
          best(copy_params(*net)) {}
};

/// A checkpoint of another network shape cannot continue: say which option differs instead of
/// letting the weight loader fail on a missing tensor.
void check_checkpoint_network(const std::string& path, torch::serialize::InputArchive& ar, const RefinerConfig& cfg) {
    const bool norm = archived_instance_norm(ar);
    if (norm != cfg.instance_norm)
        throw std::runtime_error(path + ": the checkpoint was trained with --norm " + (norm ? "instance" : "none") +
                                 "; resume with the same --norm, or start again without --resume");
    const RefinerArch arch = archived_arch(ar);
    if (arch != cfg.arch)
        throw std::runtime_error(path + ": the checkpoint was trained with --arch " + to_string(arch) +
                                 "; resume with the same --arch, or start again without --resume");
    const bool terms = archived_terms(ar);
    if (terms != cfg.terms)
        throw std::runtime_error(path + ": the checkpoint was trained with --inputs " + (terms ? "terms" : "latent") +
                                 "; resume with the same --inputs, or start again without --resume");
    const int cells = archived_emitter_cells(ar);
    if (cells != cfg.emitter_cells)
        throw std::runtime_error(path + ": the checkpoint was trained with --emitter-cells " + std::to_string(cells) +
                                 "; resume with the same --emitter-cells, or start again without --resume");
    c10::IValue v;
    if (ar.try_read("config.expansion", v) && v.toInt() != cfg.expansion)
        throw std::runtime_error(path + ": the checkpoint was trained with --expansion " + std::to_string(v.toInt()) +
                                 "; resume with the same --expansion");
}

void load_checkpoint(const std::string& path, RefinerNet& net, const RefinerConfig& cfg, TrainingState& s) {
    if (path.empty() || !std::filesystem::exists(path))
        throw std::runtime_error("refiner: --resume but no checkpoint at '" + path + "'");
    try {
        torch::serialize::InputArchive ar, net_ar, best_ar, adam_ar;
        ar.load_from(path);
        check_checkpoint_network(path, ar, cfg);
        ar.read("net", net_ar);
        net->load(net_ar);
        ar.read("best", best_ar);
        {
            RefinerNet tmp(cfg);
            tmp->load(best_ar);
            s.best = copy_params(*tmp);
        }
        ar.read("adam", adam_ar);
        s.adam.load(adam_ar);
        torch::Tensor hist;
        ar.read("history", hist);
        for (int64_t i = 0; i < hist.size(0); ++i) {
            auto r = hist[i];
            s.result.history.push_back({int(r[0].item<double>()),
                                        r[1].item<double>(),
                                        r[2].item<double>(),
                                        r[3].item<double>(),
                                        r[4].item<double>(),
                                        r[5].item<double>(),
                                        r[6].item<double>(),
                                        false,
                                        {}});
        }
        torch::Tensor st;
        ar.read("stop", st);
        s.stop.restore(st[0].item<double>(), int(st[1].item<double>()), int(st[2].item<double>()));
    } catch (const c10::Error& e) {
        throw std::runtime_error(path + ": cannot read refiner checkpoint: " + e.what_without_backtrace());
    }
    s.start = s.result.history.empty() ? 0 : s.result.history.back().iteration + 1;
    s.smoothed = s.result.history.empty() ? 0 : s.result.history.back().smoothed;
}

/// Written to a temporary file and renamed: a killed run never leaves half a checkpoint.
void save_checkpoint(const std::string& path, RefinerNet& net, const RefinerConfig& cfg, TrainingState& s) {
    if (path.empty()) return;
    torch::serialize::OutputArchive ar, net_ar, best_ar, adam_ar;
    ar.write("config.instance_norm", c10::IValue(int64_t(cfg.instance_norm)));
    ar.write("config.expansion", c10::IValue(int64_t(cfg.expansion)));
    if (cfg.arch != RefinerArch::Conv) ar.write("config.arch", c10::IValue(int64_t(cfg.arch)));
    if (cfg.terms) ar.write("config.terms", c10::IValue(int64_t(1)));
    if (cfg.emitter_cells) ar.write("config.emitter_cells", c10::IValue(int64_t(cfg.emitter_cells)));
    net->save(net_ar);
    ar.write("net", net_ar);
    RefinerNet tmp(cfg);
    put_params(*tmp, s.best);
    tmp->save(best_ar);
    ar.write("best", best_ar);
    s.adam.save(adam_ar);
    ar.write("adam", adam_ar);
    torch::Tensor hist = torch::zeros({int64_t(s.result.history.size()), 7}, torch::kFloat64);
    for (size_t i = 0; i < s.result.history.size(); ++i) {
        const RefinerRecord& r = s.result.history[i];
        const double v[7] = {double(r.iteration), r.loss, r.smoothed, r.mse, r.dssim, r.lpips, r.seconds};
        for (int k = 0; k < 7; ++k) hist[int64_t(i)][k] = v[k];
    }
    ar.write("history", hist);
    ar.write("stop", torch::tensor({s.stop.best_loss(), double(s.stop.best_iteration()), double(s.stop.bad_updates())},
                                   torch::kFloat64));
    const std::string tmp_path = path + ".tmp";
    const TemporaryFile removed_if_interrupted(tmp_path);  // Ctrl-C while saving leaves no .tmp
    ar.save_to(tmp_path);
    std::filesystem::rename(tmp_path, path);
}

/// The training examples as tensors and what each iteration's loss uses.
struct TrainingData {
    std::vector<torch::Tensor> xs;    ///< inputs [1, C + 4, h, w] per example
    std::vector<torch::Tensor> ys;    ///< target latents [1, C, h, w]
    std::vector<torch::Tensor> rgbs;  ///< target RGB [1, 3, 8h, 8w]; undefined: the decoded target
    const TorchVae* vae = nullptr;
    const Lpips* lpips = nullptr;
    int crop = 0, lpips_crop = 0;  ///< as asked; an example smaller than the crop is cropped to its size
    bool use_lpips = false, use_ssim = false;
};

torch::Tensor nchw(const std::vector<float>& hwc, int w, int h, int c) {
    return torch::from_blob(const_cast<float*>(hwc.data()), {1, h, w, c}).permute({0, 3, 1, 2}).contiguous();
}

/// Side of the training crop in an example `size` pixels long (0: the whole view).
int crop_side(int crop, int64_t size) { return crop > 0 ? std::min(crop, int(size)) : int(size); }

TrainingData training_data(const std::vector<RefinerExample>& examples, const RefinerConfig& cfg, const Vae* vae,
                           const Lpips* lpips, const RefinerTrainOptions& o) {
    if (examples.empty()) throw std::invalid_argument("refiner: no training view");
    if (!(o.input_noise >= 0.f && std::isfinite(o.input_noise)))
        throw std::invalid_argument("refiner: input noise must be >= 0, got " + std::to_string(o.input_noise));
    // the terms carry the latent's render noise too; read clean, the body could still key on it
    if (o.input_noise > 0.f && cfg.terms)
        throw std::invalid_argument("refiner: input noise beside the transport terms as inputs (read without it)");
    TrainingData d;
    const int c = cfg.latent_channels;
    int smallest = std::numeric_limits<int>::max();
    for (const RefinerExample& e : examples) {
        const int w = e.input.width, h = e.input.height;
        d.xs.push_back(refiner_input_tensor(e.input, cfg));
        if (int64_t(e.target.size()) != int64_t(w) * h * c)
            throw std::invalid_argument("refiner: target latent must be " + std::to_string(w) + "x" +
                                        std::to_string(h) + "x" + std::to_string(c));
        d.ys.push_back(nchw(e.target, w, h, c));
        if (!e.target_rgb.empty() && int64_t(e.target_rgb.size()) != int64_t(64) * w * h * 3)
            throw std::invalid_argument("refiner: target RGB must be 8w x 8h x 3");
        d.rgbs.push_back(e.target_rgb.empty() ? torch::Tensor() : nchw(e.target_rgb, 8 * w, 8 * h, 3));
        smallest = std::min({smallest, crop_side(o.crop, w), crop_side(o.crop, h)});
    }
    d.vae = vae ? torch_vae(*vae) : nullptr;
    d.lpips = lpips;
    d.crop = o.crop;
    d.lpips_crop = std::min(o.lpips_crop, smallest);
    d.use_lpips = d.vae && lpips && o.w_lpips > 0.f && d.lpips_crop > 0 && 8 * d.lpips_crop >= Lpips::kMinSize;
    d.use_ssim = o.w_ssim > 0.f && smallest >= kSsimWindow;
    return d;
}

/// Iteration `it`'s loss on its crop (w·MSE + w·D-SSIM + w·LPIPS of a decoded sub-crop); the
/// record receives the parts.
torch::Tensor crop_loss(RefinerNet& net, const TrainingData& d, const RefinerTrainOptions& o, int it,
                        RefinerRecord& r) {
    const uint64_t key = mix(o.seed ^ mix(uint64_t(it) + 1));
    torch::manual_seed(key);                               // dropout masks, input noise
    const int view = pick(key + 5, int(d.xs.size()) - 1);  // 0 without drawing when there is one example
    const torch::Tensor& x_view = d.xs[size_t(view)];
    const int w = int(x_view.size(3)), h = int(x_view.size(2));
    const int crop_w = crop_side(d.crop, w), crop_h = crop_side(d.crop, h);
    const int cx = pick(key + 1, w - crop_w), cy = pick(key + 2, h - crop_h);
    torch::Tensor x = x_view.narrow(2, cy, crop_h).narrow(3, cx, crop_w);
    torch::Tensor y = d.ys[size_t(view)].narrow(2, cy, crop_h).narrow(3, cx, crop_w);
    torch::Tensor noise;  // drawn after the seed: a resumed run draws the same
    if (o.input_noise > 0.f)
        noise = o.input_noise * torch::randn({1, int64_t(net->cfg.latent_channels), crop_h, crop_w});
    torch::Tensor out = net->forward(x, noise);
    torch::Tensor mse = torch::mse_loss(out, y);
    torch::Tensor loss = o.w_mse * mse;
    r.iteration = it;
    r.mse = mse.item<double>();
    if (d.use_ssim) {
        torch::Tensor dssim = 1.0 - ssim_torch(out, y, kLatentDataRange).mean();
        loss = loss + o.w_ssim * dssim;
        r.dssim = dssim.item<double>();
    }
    if (d.use_lpips) {
        const int lp = d.lpips_crop, lx = pick(key + 3, crop_w - lp), ly = pick(key + 4, crop_h - lp);
        torch::Tensor dec = d.vae->decode_nchw(out.narrow(2, ly, lp).narrow(3, lx, lp));
        torch::Tensor ref;
        if (d.rgbs[size_t(view)].defined()) {
            ref = d.rgbs[size_t(view)].narrow(2, 8 * (cy + ly), 8 * lp).narrow(3, 8 * (cx + lx), 8 * lp);
        } else {
            torch::NoGradGuard no_grad;
            ref = d.vae->decode_nchw(y.narrow(2, ly, lp).narrow(3, lx, lp));
        }
        torch::Tensor dist = lpips_torch(d.lpips->net(), dec * 2.0 - 1.0, ref * 2.0 - 1.0).mean();
        loss = loss + o.w_lpips * dist;
        r.lpips = dist.item<double>();
    }
    r.loss = loss.item<double>();
    return loss;
}

void set_learning_rate(torch::optim::Adam& adam, float lr) {
    for (auto& group : adam.param_groups()) static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
}

/// Back-propagates `loss`; returns "" when every weight's gradient is finite, else the first
/// weight's name whose is not (the caller then skips the optimiser step).
std::string backward_or_refuse(RefinerNet& net, torch::Tensor& loss) {
    loss.backward();
    for (const auto& p : net->named_parameters()) {
        const torch::Tensor& g = p.value().grad();
        if (g.defined() && !torch::isfinite(g).all().item<bool>()) return p.key();
    }
    return "";
}

}  // namespace

RefinerTrainResult Refiner::train(const RefinerInput& input, const std::vector<float>& target,
                                  const std::vector<float>* target_rgb, const Vae* vae, const Lpips* lpips,
                                  const RefinerTrainOptions& o,
                                  const std::function<bool(const RefinerRecord&)>& on_iteration) {
    return train(std::vector<RefinerInput>{input}, target, target_rgb, vae, lpips, o, on_iteration);
}

RefinerTrainResult Refiner::train(const std::vector<RefinerInput>& noise_views, const std::vector<float>& target,
                                  const std::vector<float>* target_rgb, const Vae* vae, const Lpips* lpips,
                                  const RefinerTrainOptions& o,
                                  const std::function<bool(const RefinerRecord&)>& on_iteration) {
    std::vector<RefinerExample> examples;
    for (const RefinerInput& v : noise_views) {
        if (v.width != noise_views[0].width || v.height != noise_views[0].height)
            throw std::invalid_argument("refiner: noise views must all be " + std::to_string(noise_views[0].width) +
                                        "x" + std::to_string(noise_views[0].height));
        examples.push_back({v, target, target_rgb ? *target_rgb : std::vector<float>{}});
    }
    return train(examples, vae, lpips, o, on_iteration);
}

RefinerTrainResult Refiner::train(const std::vector<RefinerExample>& examples, const Vae* vae, const Lpips* lpips,
                                  const RefinerTrainOptions& o,
                                  const std::function<bool(const RefinerRecord&)>& on_iteration) {
    RefinerNet& net = m->net;
    const RefinerConfig& cfg = m->config;
    const TrainingData data = training_data(examples, cfg, vae, lpips, o);
    TrainingState s(net, o);
    if (o.resume) load_checkpoint(o.checkpoint_path, net, cfg, s);
    const double seconds_before = s.result.history.empty() ? 0.0 : s.result.history.back().seconds;
    const auto t0 = std::chrono::steady_clock::now();
    bool stopped = o.patience > 0 && s.stop.bad_updates() >= o.patience;
    const CosineWarmRestarts decay(o.lr, std::max(1, o.iterations));  // a function of it: resumes on the curve
    for (int it = s.start; it < o.iterations && !stopped; ++it) {
        net->train();
        s.adam.zero_grad();
        RefinerRecord r;
        torch::Tensor loss = crop_loss(net, data, o, it, r);
        r.refused_parameter = std::isfinite(r.loss) ? backward_or_refuse(net, loss) : "loss";
        r.refused = !r.refused_parameter.empty();
        if (!r.refused) {
            if (o.cosine_decay) set_learning_rate(s.adam, decay.lr_at(it));
            s.adam.step();
            s.smoothed = it == 0 ? r.loss : kSmoothing * s.smoothed + (1 - kSmoothing) * r.loss;
        }
        r.smoothed = s.smoothed;
        r.seconds = seconds_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        s.result.history.push_back(r);
        const bool should_stop = s.stop.update(s.smoothed, it);
        if (s.stop.improved()) s.best = copy_params(*net);
        if (o.patience > 0 && should_stop) stopped = true;
        if (o.checkpoint_every > 0 && (it + 1) % o.checkpoint_every == 0)
            save_checkpoint(o.checkpoint_path, net, cfg, s);
        if (on_iteration && !on_iteration(r)) break;
    }
    save_checkpoint(o.checkpoint_path, net, cfg, s);
    put_params(*net, s.best);
    s.result.best_iteration = s.stop.best_iteration();
    s.result.best_loss = s.stop.best_loss();
    return s.result;
}

}  // namespace lpt
