// The refiner reading the transport terms beside their toned sum (--refiner-inputs terms,
// docs/refiner.md "Transport terms").
#include "refiner/refiner.h"
#include "refiner/refiner_problem.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>
#include <string>

using namespace lpt;
using namespace lpt::refiner_test;

namespace {

/// make_problem's view with terms: Ĩe and Ĩa smooth, Ĩc random, and a target that also depends
/// on Ĩc, which neither the latent nor the AOVs carry: target += 0.5 Ĩc on channel 3. Only a
/// refiner that reads the terms can learn it; one that does not can at best predict its mean.
Problem with_occlusion_residual(int w, int h, unsigned seed) {
    Problem p = make_problem(w, h);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (int i = 0; i < w * h; ++i)
        for (int t = 0; t < 3; ++t)
            for (int c = 0; c < kC; ++c) {
                const float v = t == 2 ? u(rng) : 0.5f * std::sin(0.1f * float(i % w) + float(c + 5 * t));
                p.in.terms.push_back(v);
                if (t == 2 && c == 3) p.target[size_t(i) * kC + 3] += 0.5f * v;
            }
    return p;
}

/// MSE over one latent channel: where the Ĩc-dependent residual is.
double channel_mse(const std::vector<float>& a, const std::vector<float>& b, int channel) {
    double s = 0;
    int n = 0;
    for (size_t i = size_t(channel); i < a.size(); i += kC, ++n) s += double(a[i] - b[i]) * (a[i] - b[i]);
    return s / n;
}

}  // namespace

// Starts as the identity; a view without terms is refused naming them; trained on four views
// that share latent and AOVs but not Ĩc, the terms refiner predicts the Ĩc-dependent residual of
// a fifth, where the latent-only refiner cannot do better than its mean (channel 3's MSE stays
// near the residual's variance, 0.25 / 3 ≈ 0.083); the choice survives save/load, and a
// checkpoint of the other inputs is refused naming --inputs.
TEST(Refiner, TermsInputLearnsWhatOnlyTheTermsCarry) {
    RefinerConfig cfg = small();
    cfg.terms = true;
    const Problem train = with_occlusion_residual(20, 20, 1), test = with_occlusion_residual(20, 20, 2);
    EXPECT_EQ(Refiner::create(cfg, 2)->refine(train.in), train.in.latent);
    RefinerInput bare = train.in;
    bare.terms.clear();
    try {
        Refiner::create(cfg, 2)->refine(bare);
        ADD_FAILURE() << "a view without terms was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("term"), std::string::npos) << e.what();
    }

    // Four views of the same latent and AOVs with different Ĩc: the residual is not a function of
    // the latent, so neither network can learn it by heart.
    std::vector<RefinerExample> views;
    for (unsigned k = 1; k <= 4; ++k) {
        const Problem v = with_occlusion_residual(20, 20, 10 + k);
        views.push_back({v.in, v.target, {}});
    }
    RefinerTrainOptions o = latent_training(200, 0);
    o.w_ssim = 0.f;
    o.checkpoint_path = temp_path("refiner_terms_checkpoint.pt");
    o.checkpoint_every = 100;
    auto terms = Refiner::create(cfg, 4), plain = Refiner::create(small(), 4);
    terms->train(views, nullptr, nullptr, o);
    RefinerTrainOptions po = o;
    po.checkpoint_path.clear();
    plain->train(views, nullptr, nullptr, po);
    const double with_terms = channel_mse(terms->refine(test.in), test.target, 3);
    const double without = channel_mse(plain->refine(test.in), test.target, 3);
    std::cout << "test-view MSE of channel 3: with terms " << with_terms << ", without " << without
              << " (all: " << mse(terms->refine(test.in), test.target) << ", "
              << mse(plain->refine(test.in), test.target) << ")\n";
    EXPECT_GT(without, 0.06);
    EXPECT_LT(with_terms, 0.2 * without) << "with terms " << with_terms << ", without " << without;

    const std::string path = temp_path("refiner_terms.pt");
    terms->save(path);
    auto loaded = Refiner::load(path);
    EXPECT_TRUE(loaded->config().terms);
    EXPECT_EQ(loaded->refine(test.in), terms->refine(test.in));

    RefinerTrainOptions resume = po;
    resume.checkpoint_path = o.checkpoint_path;
    resume.resume = true;
    test::expect_error_naming(
        [&] { Refiner::create(small(), 4)->train(train.in, train.target, nullptr, nullptr, nullptr, resume); },
        {"--inputs"}, "a checkpoint with terms resumed a refiner without");
}
