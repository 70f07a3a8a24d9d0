// LPIPS v0.1 (SqueezeNet) against the reference values of ../shared/models/lpips/FACTS.md (the
// example triplet of the LPIPS repository), its basic properties, and the autograd path that a
// training loss uses (vae/lpips_torch.h).
#include "core/image_io.h"
#include "test_util.h"
#include "vae/lpips.h"
#include "vae/lpips_torch.h"
#include <gtest/gtest.h>
#include <cmath>
#include <fstream>
#include <iostream>
#include <random>

using namespace lpt;

namespace {

std::string lpips_dir() {
    std::string shared = test::shared_dir();
    return shared.empty() ? std::string() : shared + "/models/lpips";
}

#define REQUIRE_LPIPS(dir)                                                      \
    const std::string dir = lpips_dir();                                        \
    if (dir.empty() || !std::ifstream(dir + "/lpips_squeeze_v0.1.safetensors")) \
        GTEST_SKIP() << "LPIPS weights not found (../shared/models/lpips; set LATENTPT_SHARED)";

const Lpips& net() {
    static std::unique_ptr<Lpips> n = Lpips::load(lpips_dir());
    return *n;
}

std::vector<float> noise_image(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    std::vector<float> v(size_t(w) * h * 3);
    for (size_t i = 0; i < v.size(); ++i)
        v[i] = 0.5f + 0.4f * std::sin(0.07f * float(i % (w * 3)) + 0.05f * float(i / (w * 3))) * u(rng);
    return v;
}

}  // namespace

TEST(Lpips, ExampleTripletMatchesReference) {
    REQUIRE_LPIPS(dir);
    const std::string t = dir + "/test_images/";
    Image ref = read_image(t + "ex_ref.png"), p0 = read_image(t + "ex_p0.png"), p1 = read_image(t + "ex_p1.png");
    ASSERT_EQ(ref.channels, 3);
    ASSERT_EQ(ref.width, 64);
    const double d0 = net().distance(ref.data, p0.data, ref.width, ref.height);
    const double d1 = net().distance(ref.data, p1.data, ref.width, ref.height);
    std::cout.precision(7);
    std::cout << "LPIPS-squeeze ex_ref/ex_p0 = " << d0 << " (reference 0.711048), ex_ref/ex_p1 = " << d1
              << " (reference 0.147902)\n";
    EXPECT_NEAR(d0, 0.711, 0.002);
    EXPECT_NEAR(d1, 0.148, 0.002);
    // FACTS.md: a faithful port reproduces the PyTorch numbers to about 1e-5.
    EXPECT_NEAR(d0, 0.711048, 2e-5);
    EXPECT_NEAR(d1, 0.147902, 2e-5);

    const double per_layer_ref[Lpips::kLayers] = {0.00989, 0.00690, 0.12881, 0.26098, 0.15068, 0.08814, 0.06564};
    std::vector<double> layers = net().layer_distances(ref.data, p0.data, ref.width, ref.height);
    ASSERT_EQ(layers.size(), size_t(Lpips::kLayers));
    double sum = 0;
    for (int k = 0; k < Lpips::kLayers; ++k) {
        EXPECT_NEAR(layers[k], per_layer_ref[k], 1e-5) << "layer " << k;
        sum += layers[k];
    }
    EXPECT_NEAR(sum, d0, 1e-6);
}

TEST(Lpips, IdenticalIsZeroAndSymmetric) {
    REQUIRE_LPIPS(dir);
    const int w = 48, h = 40;
    std::vector<float> a = noise_image(w, h, 1), b = noise_image(w, h, 2);
    EXPECT_EQ(net().distance(a, a, w, h), 0.0);
    const double ab = net().distance(a, b, w, h), ba = net().distance(b, a, w, h);
    EXPECT_GT(ab, 0.0);
    EXPECT_EQ(ab, ba);
}

TEST(Lpips, RejectsBadSizes) {
    REQUIRE_LPIPS(dir);
    std::vector<float> a(size_t(32) * 32 * 3, 0.5f);
    EXPECT_THROW(net().distance(a, a, 32, 31), std::invalid_argument);
    // Smallest accepted size works; one pixel less is a clear error, not a libtorch crash.
    const int m = Lpips::kMinSize;
    std::vector<float> s(size_t(m) * m * 3, 0.3f), t(size_t(m) * m * 3, 0.6f);
    EXPECT_GT(net().distance(s, t, m, m), 0.0);
    std::vector<float> s2(size_t(m - 1) * 40 * 3, 0.3f);
    EXPECT_THROW(net().distance(s2, s2, m - 1, 40), std::invalid_argument);
    EXPECT_THROW(Lpips::load("/nonexistent-lpips-dir"), std::runtime_error);
}

TEST(Lpips, TorchCoreHasFiniteNonZeroGradients) {
    REQUIRE_LPIPS(dir);
    const LpipsNet& n = net().net();
    torch::manual_seed(3);
    torch::Tensor a = (torch::rand({2, 3, 40, 36}) * 2 - 1).requires_grad_(true);
    torch::Tensor b = torch::rand({2, 3, 40, 36}) * 2 - 1;
    // Second batch element: all black vs all white, where whole feature columns are zero (the
    // guarded norm must keep those gradients finite).
    {
        torch::NoGradGuard ng;
        a[1].fill_(-1.0);
        b[1].fill_(1.0);
    }
    torch::Tensor d = lpips_torch(n, a, b);
    ASSERT_EQ(d.dim(), 1);
    ASSERT_EQ(d.size(0), 2);
    d.sum().backward();
    ASSERT_TRUE(a.grad().defined());
    EXPECT_TRUE(torch::isfinite(a.grad()).all().item<bool>());
    EXPECT_GT(a.grad()[0].abs().max().item<double>(), 0.0);
    EXPECT_GT(a.grad()[1].abs().max().item<double>(), 0.0);

    // Directional derivative against central differences, in double precision.
    torch::Tensor a64 = a.detach()[0].unsqueeze(0).to(torch::kFloat64).requires_grad_(true);
    torch::Tensor b64 = b[0].unsqueeze(0).to(torch::kFloat64);
    torch::Tensor v = torch::randn_like(a64);
    torch::Tensor f = lpips_torch(n, a64, b64).sum();
    f.backward();
    const double analytic = (a64.grad() * v).sum().item<double>();
    const double eps = 1e-5;
    torch::NoGradGuard ng;
    const double numeric =
        (lpips_torch(n, a64 + eps * v, b64).item<double>() - lpips_torch(n, a64 - eps * v, b64).item<double>()) /
        (2 * eps);
    EXPECT_NEAR(analytic, numeric, 1e-4 * std::max(1.0, std::abs(numeric)));
    // The plain API and the torch core agree.
    EXPECT_NEAR(lpips_torch(n, a.detach()[0].unsqueeze(0), b[0].unsqueeze(0)).item<double>(),
                lpips_torch(n, a64.detach(), b64).item<double>(), 1e-5);
}
