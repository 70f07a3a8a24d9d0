// Input noise in refiner training (RefinerTrainOptions::input_noise): the noise reaches the latent
// the body reads and not the latent its output is added to, it lowers how much the body's output
// follows a small change of its input while the refiner still learns its target, it replays on
// resume, and a negative or non-finite value is refused.
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
        RefinerTrainOptions b = mse_training(2, 11, bad);
        try {
            Refiner::create(small(), 5)->train(p.in, p.target, nullptr, nullptr, nullptr, b);
            ADD_FAILURE() << "input noise " << bad << " accepted";
        } catch (const std::invalid_argument& e) {
            EXPECT_NE(std::string(e.what()).find("input noise"), std::string::npos) << e.what();
        }
    }
}
