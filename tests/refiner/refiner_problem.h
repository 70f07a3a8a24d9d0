// Shared by the refiner tests: a toy view whose target the refiner can learn from its AOVs, and
// small networks and trainings that run in milliseconds.
#pragma once
#include "refiner/refiner.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace lpt::refiner_test {

constexpr int kC = 16;

/// A view whose "true" latent differs from the rendered one by a function of the AOVs, which
/// the refiner can learn: target = latent + 0.4 n_x on channel 0 − 0.3 distance on channel 5.
struct Problem {
    RefinerInput in;
    std::vector<float> target;
};

inline Problem make_problem(int w, int h) {
    Problem p;
    p.in.width = w;
    p.in.height = h;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float nx = std::cos(0.3f * x), ny = std::sin(0.3f * x), d = 1.f + 0.05f * float(y);
            p.in.normal.insert(p.in.normal.end(), {nx, ny, 0.f});
            p.in.distance.push_back(d);
            for (int c = 0; c < kC; ++c) {
                const float l = 0.8f * std::sin(0.2f * float(x + 3 * c)) + 0.1f * u(rng);
                p.in.latent.push_back(l);
                p.target.push_back(l + (c == 0 ? 0.4f * nx : 0.f) + (c == 5 ? -0.3f * d : 0.f));
            }
        }
    return p;
}

inline double mse(const std::vector<float>& a, const std::vector<float>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += double(a[i] - b[i]) * (a[i] - b[i]);
    return s / double(a.size());
}

inline RefinerConfig small() {
    RefinerConfig c;
    c.expansion = 2;
    c.dropout = 0.f;
    return c;
}

inline std::string temp_path(const std::string& name) { return test::write_temp_file(name, ""); }

/// Latent losses only (no decoder), a fast learning rate, no early stopping.
inline RefinerTrainOptions latent_training(int iterations, int crop) {
    RefinerTrainOptions o;
    o.iterations = iterations;
    o.lr = 3e-3f;
    o.crop = crop;
    o.w_ssim = 1.f;  // latent MSE + D-SSIM: both latent terms exercised, no decoder
    o.w_lpips = 0.f;
    o.patience = 0;
    return o;
}

/// A refiner with `cfg` starts as the identity on `in`, and refuses `lacking` (in without the
/// extra input `cfg` reads) with an std::invalid_argument naming `named`.
inline void expect_identity_and_refusal(const RefinerConfig& cfg, const RefinerInput& in, const RefinerInput& lacking,
                                        const std::string& named) {
    EXPECT_EQ(Refiner::create(cfg, 2)->refine(in), in.latent);
    test::expect_error_naming<std::invalid_argument>([&] { Refiner::create(cfg, 2)->refine(lacking); }, {named},
                                                     "a view lacking " + named + " was accepted");
}

/// MSE over one latent channel: where a test puts a residual that only one input carries.
inline double channel_mse(const std::vector<float>& a, const std::vector<float>& b, int channel) {
    double s = 0;
    int n = 0;
    for (size_t i = size_t(channel); i < a.size(); i += kC, ++n) s += double(a[i] - b[i]) * (a[i] - b[i]);
    return s / n;
}

/// Channel MSE on a held-out view of a refiner reading an extra input and of a latent-only one,
/// and the configuration the first one's saved file loads with.
struct ExtraInputScores {
    double with_input = 0, without = 0;
    RefinerConfig loaded;
};

/// The shared test of an input beside the latent and AOVs (transport terms, emitter cells): `cfg`
/// reads it, make(seed) is a view whose target depends on it on `channel`, which neither the
/// latent nor the AOVs carry. A refiner with `cfg` and a latent-only one train on four such views
/// that share latent and AOVs (seeds 11-14, 200 latent-MSE steps), so neither can learn the
/// residual by heart, and are scored on make(2). Checks on the way that the trained refiner
/// survives save/load and that a latent-only refiner refuses its checkpoint naming `option`.
template <class Make>
ExtraInputScores train_with_and_without(const RefinerConfig& cfg, Make make, int channel, const std::string& option,
                                        const std::string& name) {
    std::vector<RefinerExample> views;
    for (unsigned k = 1; k <= 4; ++k) {
        const Problem v = make(10 + k);
        views.push_back({v.in, v.target, {}});
    }
    RefinerTrainOptions o = latent_training(200, 0);
    o.w_ssim = 0.f;
    o.checkpoint_path = temp_path(name + "_checkpoint.pt");
    o.checkpoint_every = 100;
    auto with_input = Refiner::create(cfg, 4), plain = Refiner::create(small(), 4);
    with_input->train(views, nullptr, nullptr, o);
    RefinerTrainOptions po = o;
    po.checkpoint_path.clear();
    plain->train(views, nullptr, nullptr, po);
    const Problem test = make(2);
    ExtraInputScores scores{channel_mse(with_input->refine(test.in), test.target, channel),
                            channel_mse(plain->refine(test.in), test.target, channel),
                            {}};

    const std::string path = temp_path(name + ".pt");
    with_input->save(path);
    const auto loaded = Refiner::load(path);
    EXPECT_EQ(loaded->refine(test.in), with_input->refine(test.in));
    scores.loaded = loaded->config();

    RefinerTrainOptions resume = po;
    resume.checkpoint_path = o.checkpoint_path;
    resume.resume = true;
    const Problem train = make(1);
    test::expect_error_naming(
        [&] { Refiner::create(small(), 4)->train(train.in, train.target, nullptr, nullptr, nullptr, resume); },
        {option}, "a checkpoint reading " + option + " resumed a refiner without");
    return scores;
}

}  // namespace lpt::refiner_test
