// The refiner reading the transport terms beside their toned sum (--refiner-inputs terms,
// docs/refiner.md "Transport terms").
#include "refiner/refiner.h"
#include "refiner/refiner_problem.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>
#include <random>
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

}  // namespace

// Starts as the identity; a view without terms is refused naming them; trained on four views
// that share latent and AOVs but not Ĩc, the terms refiner predicts the Ĩc-dependent residual of
// a fifth, where the latent-only refiner cannot do better than its mean (channel 3's MSE stays
// near the residual's variance, 0.25 / 3 ≈ 0.083); the choice survives save/load, and a
// checkpoint of the other inputs is refused naming --inputs.
TEST(Refiner, TermsInputLearnsWhatOnlyTheTermsCarry) {
    RefinerConfig cfg = small();
    cfg.terms = true;
    const Problem train = with_occlusion_residual(20, 20, 1);
    RefinerInput bare = train.in;
    bare.terms.clear();
    expect_identity_and_refusal(cfg, train.in, bare, "term");

    const ExtraInputScores s = train_with_and_without(
        cfg, [](unsigned seed) { return with_occlusion_residual(20, 20, seed); }, 3, "--inputs", "refiner_terms");
    std::cout << "test-view MSE of channel 3: with terms " << s.with_input << ", without " << s.without << "\n";
    EXPECT_GT(s.without, 0.06);
    EXPECT_LT(s.with_input, 0.2 * s.without) << "with terms " << s.with_input << ", without " << s.without;
    EXPECT_TRUE(s.loaded.terms);
}
