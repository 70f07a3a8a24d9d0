// The compensated encoding (vae/compensated_encode.h) against a VAE whose round trip is known
// exactly: a lossless encoder (each 8 × 8 × 3 block packed into one 192-channel latent pixel)
// and a decoder that subtracts a chosen bias. Compensation must remove a bias that is constant
// over each latent cell, leave one whose cell means are zero alone, and split a sum of the two.
#include "vae/compensated_encode.h"
#include <gtest/gtest.h>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

using namespace lpt;

namespace {

constexpr int kF = 8;

/// Lossless packing as the encoder; the decoder unpacks and subtracts bias(x, y, c).
class BiasedVae : public Vae {
public:
    using Bias = std::function<float(int x, int y, int c)>;
    explicit BiasedVae(Bias bias) : bias_(std::move(bias)) { conv_.channels = 3 * kF * kF; }

    std::vector<float> encode(const std::vector<float>& rgb, int width, int height) const override {
        std::vector<float> latent(rgb.size());
        const int w = width / kF, ch = conv_.channels;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    latent[(size_t(y / kF) * w + x / kF) * ch + ((y % kF) * kF + x % kF) * 3 + c] =
                        rgb[(size_t(y) * width + x) * 3 + c];
        return latent;
    }
    std::vector<float> decode(const std::vector<float>& latent, int w, int h) const override {
        const int width = w * kF, height = h * kF, ch = conv_.channels;
        std::vector<float> rgb(latent.size());
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    rgb[(size_t(y) * width + x) * 3 + c] =
                        latent[(size_t(y / kF) * w + x / kF) * ch + ((y % kF) * kF + x % kF) * 3 + c] - bias_(x, y, c);
        return rgb;
    }
    const LatentConvention& convention() const override { return conv_; }

private:
    Bias bias_;
    LatentConvention conv_;
};

std::vector<float> random_image(int w, int h, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<float> img(size_t(w) * h * 3);
    for (float& v : img) v = u(rng);
    return img;
}

/// A smooth colour cast, constant over each latent cell (what the lowpass keeps).
float cell_cast(int x, int y, int c) { return 0.01f * float(c + 1) + 0.002f * float(x / kF) - 0.003f * float(y / kF); }

/// ±0.05 in a checkerboard of single pixels: every 8 × 8 cell's mean is 0 (what the lowpass drops).
float checker(int x, int y, int c) { return ((x + y + c) % 2 ? 0.05f : -0.05f); }

double max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
    double m = 0;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, double(std::abs(a[i] - b[i])));
    return m;
}

}  // namespace

TEST(BlockMean, ReplacesEachBlockByItsMeanPerChannel) {
    // 2 x 2 blocks of a 4 x 2 two-channel image, means by hand.
    const std::vector<float> img = {1, 10, 2, 20, 5, 50, 7, 70,  //
                                    3, 30, 4, 40, 6, 60, 8, 80};
    const std::vector<float> want = {2.5f, 25, 2.5f, 25, 6.5f, 65, 6.5f, 65,  //
                                     2.5f, 25, 2.5f, 25, 6.5f, 65, 6.5f, 65};
    EXPECT_EQ(block_mean(img, 4, 2, 2, 2), want);
    EXPECT_THROW(block_mean(img, 4, 2, 2, 3), std::invalid_argument);
    EXPECT_THROW(block_mean(img, 2, 2, 2, 2), std::invalid_argument);
}

TEST(CompensatedEncode, RemovesACastThatIsConstantOverEachLatentCell) {
    const int w = 32, h = 24;
    const std::vector<float> x = random_image(w, h, 1);
    const BiasedVae vae(cell_cast);
    const std::vector<float> plain = vae.decode(vae.encode(x, w, h), w / kF, h / kF);
    const std::vector<float> compensated = vae.decode(encode_compensated(vae, x, w, h), w / kF, h / kF);
    EXPECT_GT(max_abs_diff(plain, x), 0.02);        // the cast is there without compensation
    EXPECT_LT(max_abs_diff(compensated, x), 1e-6);  // and gone with it
}

TEST(CompensatedEncode, LeavesABiasWithZeroCellMeansAlone) {
    const int w = 16, h = 16;
    const std::vector<float> x = random_image(w, h, 2);
    const BiasedVae vae(checker);
    EXPECT_LT(max_abs_diff(encode_compensated(vae, x, w, h), vae.encode(x, w, h)), 1e-6);
}

TEST(CompensatedEncode, SplitsABiasIntoTheCastItRemovesAndTheDetailItKeeps) {
    const int w = 24, h = 16;
    const std::vector<float> x = random_image(w, h, 3);
    const BiasedVae vae([](int px, int py, int c) { return cell_cast(px, py, c) + checker(px, py, c); });
    const std::vector<float> decoded = vae.decode(encode_compensated(vae, x, w, h), w / kF, h / kF);
    std::vector<float> want(x.size());
    for (int y = 0; y < h; ++y)
        for (int px = 0; px < w; ++px)
            for (int c = 0; c < 3; ++c)
                want[(size_t(y) * w + px) * 3 + c] = x[(size_t(y) * w + px) * 3 + c] - checker(px, y, c);
    EXPECT_LT(max_abs_diff(decoded, want), 1e-6);
}

TEST(CompensatedEncode, CoarserBlocksRemoveOnlyTheCastCommonToEachBlock) {
    // A cast uniform over each 16-pixel block plus a ±0.04 one alternating between its four
    // latent cells: 8-pixel blocks remove both, 16-pixel blocks the uniform part alone.
    const int w = 32, h = 32;
    const std::vector<float> x = random_image(w, h, 4);
    auto uniform = [](int px, int py, int c) { return 0.02f * float(c + 1) + 0.01f * float(px / 16 + py / 16); };
    auto alternating = [](int px, int py, int) { return (px / kF + py / kF) % 2 ? 0.04f : -0.04f; };
    const BiasedVae vae([&](int px, int py, int c) { return uniform(px, py, c) + alternating(px, py, c); });
    std::vector<float> want(x.size());
    for (int y = 0; y < h; ++y)
        for (int px = 0; px < w; ++px)
            for (int c = 0; c < 3; ++c)
                want[(size_t(y) * w + px) * 3 + c] = x[(size_t(y) * w + px) * 3 + c] - alternating(px, y, c);
    EXPECT_LT(max_abs_diff(vae.decode(encode_compensated(vae, x, w, h, 16), w / kF, h / kF), want), 1e-6);
    EXPECT_LT(max_abs_diff(vae.decode(encode_compensated(vae, x, w, h, kF), w / kF, h / kF), x), 1e-6);
    EXPECT_EQ(encode_compensated(vae, x, w, h, 0), encode_compensated(vae, x, w, h, kF));  // 0: one latent cell
}
