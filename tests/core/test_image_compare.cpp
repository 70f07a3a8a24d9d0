// The render comparison's statistics (core/image_compare.h) against synthetic renders with known
// noise and known bias: noise alone must give z-scores of unit spread and (almost) no flags, and
// a bias of a few noise standard deviations must be found where it was put.
#include "core/image_compare.h"
#include <gtest/gtest.h>
#include <cmath>
#include <random>

using namespace lpt;

namespace {

/// K renders of a smooth image (a ramp with an edge, so blocks differ in level) with Gaussian
/// pixel noise of relative size `noise`, scaled by `gain` inside the rectangle [x0, x1) x [y0, y1).
RenderStack noisy_stack(int w, int h, int k, double noise, uint32_t seed, double gain = 1.0, int x0 = 0, int x1 = 0,
                        int y0 = 0, int y1 = 0) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> gauss(0.0, 1.0);
    RenderStack s;
    s.width = w;
    s.height = h;
    for (int r = 0; r < k; ++r) {
        std::vector<float> img(size_t(w) * h * 3);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    double v = 0.2 + 0.6 * x / w + (y > h / 2 ? 0.5 : 0.0) + 0.1 * c;
                    if (x >= x0 && x < x1 && y >= y0 && y < y1) v *= gain;
                    img[(size_t(y) * w + x) * 3 + c] = float(v * (1.0 + noise * gauss(rng)));
                }
        s.renders.push_back(std::move(img));
    }
    return s;
}

}  // namespace

TEST(ImageCompare, NoiseAloneGivesUnitZSpreadAndFewFlags) {
    // 32 x 32 blocks of 16^2 pixels; two renders per side estimate each side's noise.
    const int w = 512, h = 512;
    RenderStack a = noisy_stack(w, h, 2, 0.3, 1), b = noisy_stack(w, h, 2, 0.3, 2);
    ImageComparison c = compare_renders(a, b, {}, 16, 3.0);
    ASSERT_EQ(c.blocks.size(), 1024u);
    double z2 = 0;
    for (const auto& blk : c.blocks) z2 += blk.z * blk.z;
    const double z_rms = std::sqrt(z2 / double(c.blocks.size()));
    // With two renders the per-pixel variance has 1 degree of freedom, but a block sums 256 of
    // them, so its variance estimate is good to ~9 %: the z spread is 1 within a few percent.
    EXPECT_NEAR(z_rms, 1.0, 0.1);
    EXPECT_LE(c.flagged, 8) << "3 sigma flags ~0.3 % of 1024 blocks under noise alone";
    for (int ch = 0; ch < 3; ++ch) EXPECT_LT(std::abs(c.mean_ratio[ch] - 1.0), 4 * c.mean_ratio_sigma[ch]);
}

TEST(ImageCompare, LocalBiasIsFlaggedWhereItIs) {
    const int w = 256, h = 256;
    // +3 % in one 32 x 32 block: each block mean has ~0.3 / 32 / sqrt(2) ≈ 0.7 % noise per side.
    RenderStack a = noisy_stack(w, h, 2, 0.3, 3, 1.03, 64, 96, 128, 160), b = noisy_stack(w, h, 2, 0.3, 4);
    ImageComparison c = compare_renders(a, b, {}, 32, 3.0);
    const auto& biased = c.blocks[size_t(128 / 32) * size_t(c.blocks_x) + 64 / 32];
    EXPECT_TRUE(biased.flagged) << "z = " << biased.z;
    EXPECT_NEAR(biased.ratio, 1.03, 0.02);
    EXPECT_LE(c.flagged, 2);
}

TEST(ImageCompare, UnknownNoiseFlagsNothingAndMaskRemovesPixels) {
    const int w = 64, h = 64;
    RenderStack a = noisy_stack(w, h, 1, 0.0, 5, 2.0, 0, 64, 0, 32), b = noisy_stack(w, h, 1, 0.0, 6);
    // Without a noise estimate no block can be called significant, whatever its ratio.
    ImageComparison c = compare_renders(a, b, {}, 32, 3.0);
    EXPECT_EQ(c.flagged, 0);
    EXPECT_FALSE(c.test_noise_known);
    // Masking the doubled half leaves exact agreement.
    std::vector<uint8_t> mask(size_t(w) * h, 0);
    for (int i = 0; i < w * 32; ++i) mask[i] = 1;
    ImageComparison m = compare_renders(a, b, mask, 32, 3.0);
    EXPECT_EQ(m.masked_pixels, w * 32);
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(m.mean_ratio[ch], 1.0, 1e-6);
    EXPECT_NEAR(m.rel_mse, 0.0, 1e-12);
    EXPECT_EQ(m.blocks[0].pixels, 0);
}

TEST(ImageCompare, MismatchedInputsAreErrors) {
    RenderStack a = noisy_stack(8, 8, 1, 0.1, 7), b = noisy_stack(16, 8, 1, 0.1, 8);
    EXPECT_THROW(compare_renders(a, b, {}, 4), std::invalid_argument);
    RenderStack empty;
    EXPECT_THROW(compare_renders(empty, a, {}, 4), std::invalid_argument);
    EXPECT_THROW(compare_renders(a, a, std::vector<uint8_t>(3, 0), 4), std::invalid_argument);
}

// Equal renders on a side (one file given twice, or a noise-free set-up) estimate zero noise,
// and a zero sigma flags no block however biased: their noise counts as unknown instead.
TEST(ImageCompare, EqualRendersLeaveTheirNoiseUnknown) {
    RenderStack twice = noisy_stack(8, 8, 2, 0.1, 9), biased = noisy_stack(8, 8, 2, 0.1, 10, 1.2, 0, 4, 0, 4);
    twice.renders[1] = twice.renders[0];
    const ImageComparison c = compare_renders(twice, twice, {}, 4);
    EXPECT_FALSE(c.test_noise_known);
    EXPECT_FALSE(c.ref_noise_known);
    EXPECT_TRUE(compare_renders(twice, biased, {}, 4).ref_noise_known);
}
