// Input noise in refiner training (RefinerTrainOptions::input_noise): the noise reaches the latent
// the body reads and neither the latent its output is added to nor the AOVs, it lowers how much the
// body's output follows a small change of its input while the refiner still learns its target, it
// replays on resume, and a negative or non-finite value, or noise beside the transport terms as
// inputs, is refused.
#include "refiner/refiner.h"
#include "refiner/refiner_problem.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

using namespace lpt;
using namespace lpt::refiner_test;

namespace {

/// Latent MSE alone, so that a record's mse is the whole loss.
RefinerTrainOptions mse_training(int iterations, int crop, float input_noise) {
    RefinerTrainOptions o = latent_training(iterations, crop);
    o.w_ssim = 0.f;
    o.input_noise = input_noise;
    return o;
}

/// How strongly the body answers a small change δ of the latent: E|f(x + δ) − δ − f(x)|² / E|δ|².
/// The refiner adds its body's output to the latent, so the δ that passes straight through is
/// taken out; 0 = a body that ignores the latent, 1 = one that cancels δ (a denoiser of it).
double body_sensitivity(const Refiner& r, const RefinerInput& in) {
    std::mt19937 rng(21);
    std::normal_distribution<float> g(0.f, 0.05f);
    RefinerInput moved = in;
    std::vector<float> delta(in.latent.size());
    for (size_t i = 0; i < delta.size(); ++i) moved.latent[i] += delta[i] = g(rng);
    const std::vector<float> base = r.refine(in), out = r.refine(moved);
    double num = 0, den = 0;
    for (size_t i = 0; i < out.size(); ++i) {
        const double body_change = double(out[i]) - delta[i] - base[i];
        num += body_change * body_change;
        den += double(delta[i]) * delta[i];
    }
    return num / den;
}

}  // namespace

// With lr 0 the network stays the identity (its head starts at zero, so the body adds exactly 0):
// the output is the latent whatever the body reads. Noise on the body's input must then leave
// every step's loss as it is; noise on the latent the output is added to would add σ² to it.
TEST(RefinerInputNoise, ReachesTheBodyNotTheLatentItIsAddedTo) {
    const Problem p = make_problem(16, 16);
    RefinerTrainOptions clean = mse_training(30, 12, 0.f), noisy = mse_training(30, 12, 0.5f);
    clean.lr = noisy.lr = 0.f;
    const RefinerTrainResult a = Refiner::create(small(), 3)->train(p.in, p.target, nullptr, nullptr, nullptr, clean);
    const RefinerTrainResult b = Refiner::create(small(), 3)->train(p.in, p.target, nullptr, nullptr, nullptr, noisy);
    ASSERT_EQ(a.history.size(), b.history.size());
    for (size_t i = 0; i < a.history.size(); ++i) EXPECT_EQ(a.history[i].mse, b.history[i].mse) << "step " << i;
}

// A residual only the AOVs tell: every pixel draws its own n_x and distance d in [1, 2], the
// latent is the same everywhere, and the target is latent + 0.4 n_x on channel 0, + 0.8 − 0.6 d on
// channel 5. Trained with noise (σ = 2) on the latent, the body must still learn it from the AOVs;
// had the noise reached them, nothing would tell one pixel from another (a per-pixel draw, which
// no spatial average recovers) and it could learn no more than the residual's mean.
TEST(RefinerInputNoise, LeavesTheAovsClean) {
    Problem p;
    p.in.width = p.in.height = 16;
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (int i = 0; i < 16 * 16; ++i) {
        const float nx = u(rng), d = 1.5f + 0.5f * u(rng);
        p.in.normal.insert(p.in.normal.end(), {nx, std::sqrt(1.f - nx * nx), 0.f});
        p.in.distance.push_back(d);
        for (int c = 0; c < kC; ++c) {
            p.in.latent.push_back(0.3f * std::sin(float(c)));
            p.target.push_back(p.in.latent.back() + (c == 0 ? 0.4f * nx : 0.f) + (c == 5 ? 0.8f - 0.6f * d : 0.f));
        }
    }
    auto r = Refiner::create(small(), 5);
    r->train(p.in, p.target, nullptr, nullptr, nullptr, mse_training(300, 12, 2.f));
    const std::vector<float> refined = r->refine(p.in);
    for (int channel : {0, 5}) {
        const double before = channel_mse(p.in.latent, p.target, channel);
        const double after = channel_mse(refined, p.target, channel);
        EXPECT_LT(after, 0.2 * before) << "channel " << channel << ": unrefined " << before << ", refined " << after;
    }
}

// The toy target depends on the AOVs only, so a body that ignores the latent loses nothing; trained
// with noise on the latent it reads, it must follow a small change of the latent markedly less
// than the same body trained without, and still learn most of the target.
TEST(RefinerInputNoise, LowersTheBodysSensitivityAndStillLearns) {
    const Problem p = make_problem(16, 16);
    const double before = mse(p.in.latent, p.target);
    auto clean = Refiner::create(small(), 5), noisy = Refiner::create(small(), 5);
    const RefinerTrainResult a = clean->train(p.in, p.target, nullptr, nullptr, nullptr, mse_training(150, 12, 0.f));
    const RefinerTrainResult b = noisy->train(p.in, p.target, nullptr, nullptr, nullptr, mse_training(150, 12, 0.5f));
    ASSERT_NE(a.history.back().loss, b.history.back().loss) << "the noise changed nothing";
    const double s_clean = body_sensitivity(*clean, p.in), s_noisy = body_sensitivity(*noisy, p.in);
    EXPECT_LT(s_noisy, 0.5 * s_clean) << "clean " << s_clean << ", noisy " << s_noisy;
    EXPECT_LT(mse(noisy->refine(p.in), p.target), 0.25 * before);
}

TEST(RefinerInputNoise, ReplaysOnResumeAndRefusesBadValues) {
    const Problem p = make_problem(14, 12);
    RefinerTrainOptions o = mse_training(12, 11, 0.3f);
    o.seed = 9;
    auto full = Refiner::create(small(), 5);
    full->train(p.in, p.target, nullptr, nullptr, nullptr, o);

    o.checkpoint_path = temp_path("input_noise_ck.pt");
    o.checkpoint_every = 0;
    o.iterations = 5;  // "killed" after 5 steps; the checkpoint is written at the end
    Refiner::create(small(), 5)->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    auto resumed = Refiner::create(small(), 77);
    o.iterations = 12;
    o.resume = true;
    resumed->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    EXPECT_EQ(resumed->refine(p.in), full->refine(p.in));

    for (float bad : {-0.1f, std::numeric_limits<float>::quiet_NaN()}) {
        const RefinerTrainOptions b = mse_training(2, 11, bad);
        test::expect_error_naming<std::invalid_argument>(
            [&] { Refiner::create(small(), 5)->train(p.in, p.target, nullptr, nullptr, nullptr, b); }, {"input noise"},
            "input noise " + std::to_string(bad) + " accepted");
    }
}

// The transport terms carry the latent's render noise; the noise is drawn for the latent alone, so
// the pair is refused (by name) rather than trained with the terms read clean.
TEST(RefinerInputNoise, RefusedBesideTheTransportTerms) {
    Problem p = make_problem(12, 12);
    p.in.terms.assign(p.in.latent.size() * 3, 0.25f);
    RefinerConfig cfg = small();
    cfg.terms = true;
    Refiner::create(cfg, 5)->train(p.in, p.target, nullptr, nullptr, nullptr, mse_training(2, 11, 0.f));
    test::expect_error_naming<std::invalid_argument>(
        [&] { Refiner::create(cfg, 5)->train(p.in, p.target, nullptr, nullptr, nullptr, mse_training(2, 11, 0.1f)); },
        {"input noise", "transport terms"}, "input noise beside the terms accepted");
}
