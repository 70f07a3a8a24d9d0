// SSIM (vae/ssim.h): exact values on hand-computable inputs, agreement with an independent
// naive implementation (full 2-D window, centred moments), symmetry, and the differentiable
// libtorch version (vae/lpips_torch.h) against the plain one.
#include "test_util.h"
#include "vae/lpips_torch.h"
#include "vae/ssim.h"
#include <gtest/gtest.h>
#include <cmath>
#include <random>
#include <vector>

using namespace lpt;

namespace {

/// Deterministic structured noise, values in [lo, hi], interleaved w x h x c.
std::vector<float> pattern(int w, int h, int c, uint32_t seed, float lo = 0.f, float hi = 1.f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<float> v(size_t(w) * h * c);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < c; ++k) {
                const float s = 0.5f + 0.35f * std::sin(0.3f * x + 0.7f * k) * std::cos(0.2f * y + float(seed)) +
                                0.15f * (u(rng) - 0.5f);
                v[(size_t(y) * w + x) * c + k] = lo + (hi - lo) * s;
            }
    return v;
}

/// Textbook SSIM, written independently of vae/ssim.cpp: the 11x11 window built as a 2-D
/// Gaussian normalised over all 121 taps, and the variances/covariance as centred sums
/// sum w (x - mu)(y - mu) rather than E[xy] - mu_x mu_y.
double naive_ssim(const std::vector<float>& a, const std::vector<float>& b, int w, int h, int ch, double L) {
    double win[11][11], norm = 0;
    for (int i = 0; i < 11; ++i)
        for (int j = 0; j < 11; ++j)
            norm += win[i][j] = std::exp(-((i - 5) * (i - 5) + (j - 5) * (j - 5)) / (2 * 1.5 * 1.5));
    for (auto& row : win)
        for (double& v : row) v /= norm;
    const double C1 = (0.01 * L) * (0.01 * L), C2 = (0.03 * L) * (0.03 * L);
    double total = 0;
    for (int k = 0; k < ch; ++k) {
        double sum = 0;
        int count = 0;
        for (int y0 = 0; y0 + 11 <= h; ++y0)
            for (int x0 = 0; x0 + 11 <= w; ++x0) {
                auto at = [&](const std::vector<float>& img, int i, int j) {
                    return double(img[(size_t(y0 + i) * w + x0 + j) * ch + k]);
                };
                double ma = 0, mb = 0;
                for (int i = 0; i < 11; ++i)
                    for (int j = 0; j < 11; ++j) {
                        ma += win[i][j] * at(a, i, j);
                        mb += win[i][j] * at(b, i, j);
                    }
                double va = 0, vb = 0, cab = 0;
                for (int i = 0; i < 11; ++i)
                    for (int j = 0; j < 11; ++j) {
                        const double da = at(a, i, j) - ma, db = at(b, i, j) - mb;
                        va += win[i][j] * da * da;
                        vb += win[i][j] * db * db;
                        cab += win[i][j] * da * db;
                    }
                sum += (2 * ma * mb + C1) * (2 * cab + C2) / ((ma * ma + mb * mb + C1) * (va + vb + C2));
                ++count;
            }
        total += sum / count;
    }
    return total / ch;
}

torch::Tensor to_nchw(const std::vector<float>& v, int w, int h, int c) {
    return torch::from_blob(const_cast<float*>(v.data()), {1, h, w, c}).permute({0, 3, 1, 2}).contiguous();
}

}  // namespace

TEST(Ssim, IdenticalIsOne) {
    for (int c : {1, 3, 16}) {
        std::vector<float> a = pattern(23, 17, c, 4);
        EXPECT_NEAR(ssim(a.data(), a.data(), 23, 17, c, 1.0), 1.0, 1e-12) << c << " channels";
    }
}

TEST(Ssim, ConstantImagesHaveTheClosedForm) {
    // Both images flat: every variance and covariance is 0, so the contrast-structure factor is
    // C2 / C2 = 1 and SSIM = (2 mu_a mu_b + C1) / (mu_a^2 + mu_b^2 + C1) at every position.
    for (double L : {1.0, 6.0}) {
        const float ma = 0.25f, mb = 0.75f;
        std::vector<float> a(size_t(20) * 14 * 2, ma), b(size_t(20) * 14 * 2, mb);
        const double C1 = (0.01 * L) * (0.01 * L);
        const double expect = (2.0 * ma * mb + C1) / (double(ma) * ma + double(mb) * mb + C1);
        EXPECT_NEAR(ssim(a.data(), b.data(), 20, 14, 2, L), expect, 1e-12) << "L = " << L;
    }
    // One flat channel and one different channel average per channel.
    std::vector<float> a(size_t(11) * 11 * 2), b(size_t(11) * 11 * 2);
    for (size_t i = 0; i < a.size(); i += 2) a[i] = 0.5f, b[i] = 0.5f, a[i + 1] = 0.f, b[i + 1] = 1.f;
    const double C1 = 1e-4;
    EXPECT_NEAR(ssim(a.data(), b.data(), 11, 11, 2, 1.0), 0.5 * (1.0 + C1 / (1.0 + C1)), 1e-12);
}

TEST(Ssim, MatchesNaiveReferenceAndIsSymmetric) {
    struct Case {
        int w, h, c;
        double L;
        float lo, hi;
    };
    for (const Case& k :
         {Case{11, 11, 1, 1.0, 0.f, 1.f}, Case{19, 13, 3, 1.0, 0.f, 1.f}, Case{16, 16, 16, 6.0, -3.f, 3.f}}) {
        std::vector<float> a = pattern(k.w, k.h, k.c, 1, k.lo, k.hi), b = pattern(k.w, k.h, k.c, 2, k.lo, k.hi);
        const double ref = naive_ssim(a, b, k.w, k.h, k.c, k.L);
        const double ab = ssim(a.data(), b.data(), k.w, k.h, k.c, k.L),
                     ba = ssim(b.data(), a.data(), k.w, k.h, k.c, k.L);
        EXPECT_NEAR(ab, ref, 1e-10) << k.w << "x" << k.h << "x" << k.c;
        EXPECT_NEAR(ab, ba, 1e-14);
        EXPECT_LT(ab, 0.999);
        EXPECT_GT(ab, -1.0);
    }
}

TEST(Ssim, RejectsBadArguments) {
    std::vector<float> a(size_t(10) * 20, 0.f);
    EXPECT_THROW(ssim(a.data(), a.data(), 10, 20, 1, 1.0), std::invalid_argument);
    EXPECT_THROW(ssim(a.data(), a.data(), 20, 10, 1, 1.0), std::invalid_argument);
    EXPECT_THROW(ssim(a.data(), a.data(), 20, 10, 0, 1.0), std::invalid_argument);
    std::vector<float> b(size_t(12) * 12, 0.f);
    EXPECT_THROW(ssim(b.data(), b.data(), 12, 12, 1, 0.0), std::invalid_argument);
}

TEST(Ssim, TorchVersionMatchesPlainAndIsDifferentiable) {
    const int w = 27, h = 21;
    for (int c : {3, 16}) {
        const double L = c == 3 ? 1.0 : 6.0;
        const float lo = c == 3 ? 0.f : -3.f, hi = c == 3 ? 1.f : 3.f;
        std::vector<float> a = pattern(w, h, c, 5, lo, hi), b = pattern(w, h, c, 6, lo, hi);
        const double plain = ssim(a.data(), b.data(), w, h, c, L);
        torch::Tensor ta = to_nchw(a, w, h, c), tb = to_nchw(b, w, h, c);
        const double t64 = ssim_torch(ta.to(torch::kFloat64), tb.to(torch::kFloat64), L).item<double>();
        const double t32 = ssim_torch(ta, tb, L).item<double>();
        EXPECT_NEAR(t64, plain, 1e-6) << c << " channels";
        EXPECT_NEAR(t64, plain, 1e-12) << c << " channels";
        EXPECT_NEAR(t32, plain, 1e-5) << c << " channels (float32)";

        torch::Tensor x = ta.clone().requires_grad_(true);
        torch::Tensor s = ssim_torch(x, tb, L);
        ASSERT_EQ(s.dim(), 1);
        s.sum().backward();
        EXPECT_TRUE(torch::isfinite(x.grad()).all().item<bool>());
        EXPECT_GT(x.grad().abs().max().item<double>(), 0.0);
    }
}
