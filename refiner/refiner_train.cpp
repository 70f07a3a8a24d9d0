// Refiner training (stage 2): Adam on MSE + (1 − SSIM) of latents plus LPIPS of decoded crops,
// on random crops of the training view so an iteration stays cheap on a CPU. Crop positions and
// dropout masks are functions of (seed, iteration), so a resumed run repeats the same iterations
// as an uninterrupted one.
#include "autodiff/lr_schedule.h"
#include "core/sampler.h"
#include "refiner/refiner_net.h"
#include "vae/lpips_torch.h"
#include "vae/ssim.h"
#include "vae/vae_torch.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
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

}  // namespace

RefinerTrainResult Refiner::train(const RefinerInput& input, const std::vector<float>& target, const std::vector<float>* target_rgb,
                                  const Vae* vae, const Lpips* lpips, const RefinerTrainOptions& o,
                                  const std::function<bool(const RefinerRecord&)>& on_iteration) {
    RefinerNet& net = m->net;
    const RefinerConfig& cfg = m->config;
    const int w = input.width, h = input.height, c = cfg.latent_channels;
    torch::Tensor x_all = refiner_input_tensor(input, cfg);
    if (int64_t(target.size()) != int64_t(w) * h * c)
        throw std::invalid_argument("refiner: target latent must be " + std::to_string(w) + "x" + std::to_string(h) + "x" + std::to_string(c));
    torch::Tensor y_all = torch::from_blob(const_cast<float*>(target.data()), {1, h, w, c}).permute({0, 3, 1, 2}).contiguous();
    torch::Tensor rgb_all;
    if (target_rgb) {
        if (int64_t(target_rgb->size()) != int64_t(64) * w * h * 3) throw std::invalid_argument("refiner: target RGB must be 8w x 8h x 3");
        rgb_all = torch::from_blob(const_cast<float*>(target_rgb->data()), {1, 8 * h, 8 * w, 3}).permute({0, 3, 1, 2}).contiguous();
    }
    const TorchVae* tvae = vae ? torch_vae(*vae) : nullptr;
    const int crop_w = o.crop > 0 ? std::min(o.crop, w) : w, crop_h = o.crop > 0 ? std::min(o.crop, h) : h;
    const int lp = std::min({o.lpips_crop, crop_w, crop_h});
    const bool use_lpips = tvae && lpips && o.w_lpips > 0.f && lp > 0 && 8 * lp >= Lpips::kMinSize;
    const bool use_ssim = o.w_ssim > 0.f && crop_w >= kSsimWindow && crop_h >= kSsimWindow;

    torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(o.lr));
    RefinerTrainResult result;
    int start = 0;
    double smoothed = 0;
    EarlyStopping stop(std::max(1, o.patience), o.min_delta);
    ParamCopy best = copy_params(*net);
    if (o.resume) {
        if (o.checkpoint_path.empty() || !std::filesystem::exists(o.checkpoint_path))
            throw std::runtime_error("refiner: --resume but no checkpoint at '" + o.checkpoint_path + "'");
        try {
            torch::serialize::InputArchive ar, net_ar, best_ar, adam_ar;
            ar.load_from(o.checkpoint_path);
            ar.read("net", net_ar);
            net->load(net_ar);
            ar.read("best", best_ar);
            {
                RefinerNet tmp(cfg);
                tmp->load(best_ar);
                best = copy_params(*tmp);
            }
            ar.read("adam", adam_ar);
            adam.load(adam_ar);
            torch::Tensor hist;
            ar.read("history", hist);
            for (int64_t i = 0; i < hist.size(0); ++i) {
                auto r = hist[i];
                result.history.push_back({int(r[0].item<double>()), r[1].item<double>(), r[2].item<double>(), r[3].item<double>(),
                                          r[4].item<double>(), r[5].item<double>(), r[6].item<double>()});
            }
            torch::Tensor st;
            ar.read("stop", st);
            stop.restore(st[0].item<double>(), int(st[1].item<double>()), int(st[2].item<double>()));
        } catch (const c10::Error& e) {
            throw std::runtime_error(o.checkpoint_path + ": cannot read refiner checkpoint: " + e.what_without_backtrace());
        }
        start = result.history.empty() ? 0 : result.history.back().iteration + 1;
        smoothed = result.history.empty() ? 0 : result.history.back().smoothed;
    }
    auto save_checkpoint = [&]() {
        if (o.checkpoint_path.empty()) return;
        torch::serialize::OutputArchive ar, net_ar, best_ar, adam_ar;
        net->save(net_ar);
        ar.write("net", net_ar);
        RefinerNet tmp(cfg);
        put_params(*tmp, best);
        tmp->save(best_ar);
        ar.write("best", best_ar);
        adam.save(adam_ar);
        ar.write("adam", adam_ar);
        torch::Tensor hist = torch::zeros({int64_t(result.history.size()), 7}, torch::kFloat64);
        for (size_t i = 0; i < result.history.size(); ++i) {
            const RefinerRecord& r = result.history[i];
            const double v[7] = {double(r.iteration), r.loss, r.smoothed, r.mse, r.dssim, r.lpips, r.seconds};
            for (int k = 0; k < 7; ++k) hist[int64_t(i)][k] = v[k];
        }
        ar.write("history", hist);
        ar.write("stop", torch::tensor({stop.best_loss(), double(stop.best_iteration()), double(stop.bad_updates())}, torch::kFloat64));
        const std::string tmp_path = o.checkpoint_path + ".tmp";
        ar.save_to(tmp_path);
        std::filesystem::rename(tmp_path, o.checkpoint_path);
    };

    const double seconds_before = result.history.empty() ? 0.0 : result.history.back().seconds;
    const auto t0 = std::chrono::steady_clock::now();
    bool stopped = o.patience > 0 && stop.bad_updates() >= o.patience;
    for (int it = start; it < o.iterations && !stopped; ++it) {
        const uint64_t key = mix(o.seed ^ mix(uint64_t(it) + 1));
        torch::manual_seed(key);  // dropout masks
        const int cx = pick(key + 1, w - crop_w), cy = pick(key + 2, h - crop_h);
        torch::Tensor x = x_all.narrow(2, cy, crop_h).narrow(3, cx, crop_w);
        torch::Tensor y = y_all.narrow(2, cy, crop_h).narrow(3, cx, crop_w);
        net->train();
        adam.zero_grad();
        torch::Tensor out = net->forward(x);
        torch::Tensor mse = torch::mse_loss(out, y);
        torch::Tensor loss = o.w_mse * mse;
        RefinerRecord r;
        r.iteration = it;
        r.mse = mse.item<double>();
        if (use_ssim) {
            torch::Tensor dssim = 1.0 - ssim_torch(out, y, kLatentDataRange).mean();
            loss = loss + o.w_ssim * dssim;
            r.dssim = dssim.item<double>();
        }
        if (use_lpips) {
            const int lx = pick(key + 3, crop_w - lp), ly = pick(key + 4, crop_h - lp);
            torch::Tensor dec = tvae->decode_nchw(out.narrow(2, ly, lp).narrow(3, lx, lp));
            torch::Tensor ref;
            if (rgb_all.defined()) {
                ref = rgb_all.narrow(2, 8 * (cy + ly), 8 * lp).narrow(3, 8 * (cx + lx), 8 * lp);
            } else {
                torch::NoGradGuard no_grad;
                ref = tvae->decode_nchw(y.narrow(2, ly, lp).narrow(3, lx, lp));
            }
            torch::Tensor d = lpips_torch(lpips->net(), dec * 2.0 - 1.0, ref * 2.0 - 1.0).mean();
            loss = loss + o.w_lpips * d;
            r.lpips = d.item<double>();
        }
        r.loss = loss.item<double>();
        if (!std::isfinite(r.loss)) throw std::runtime_error("refiner: loss became non-finite at iteration " + std::to_string(it));
        loss.backward();
        adam.step();
        smoothed = it == 0 ? r.loss : kSmoothing * smoothed + (1 - kSmoothing) * r.loss;
        r.smoothed = smoothed;
        r.seconds = seconds_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        result.history.push_back(r);
        const bool should_stop = stop.update(smoothed, it);
        if (stop.improved()) best = copy_params(*net);
        if (o.patience > 0 && should_stop) stopped = true;
        if (o.checkpoint_every > 0 && (it + 1) % o.checkpoint_every == 0) save_checkpoint();
        if (on_iteration && !on_iteration(r)) break;
    }
    save_checkpoint();
    put_params(*net, best);
    result.best_iteration = stop.best_iteration();
    result.best_loss = stop.best_loss();
    return result;
}

}  // namespace lpt
