// The inline warps: the polynomial sin/cos against libm, the concentric map against its
// closed form (docs/sampling.md), and the cosine hemisphere's density by a histogram in cos θ.
#include "core/sampler.h"
#include "core/warp.h"
#include <gtest/gtest.h>
#include <cmath>
#include <vector>

using namespace lpt;

TEST(Warp, QuarterPiSinCosMatchesLibm) {
    double worst = 0;
    for (int i = 0; i <= 20000; ++i) {
        const float a = -0.25f * kPi + 0.5f * kPi * float(i) / 20000.f;
        float s, c;
        sincos_quarter_pi(a, s, c);
        worst = std::max({worst, std::abs(double(s) - std::sin(double(a))), std::abs(double(c) - std::cos(double(a)))});
    }
    EXPECT_LT(worst, 2e-7) << "a few float ulps at most";
}

TEST(Warp, ConcentricDiskMatchesClosedForm) {
    for (int i = 0; i < 4096; ++i) {
        const Vec2f u(sample_1d(3, uint32_t(i), 0, 0), sample_1d(3, uint32_t(i), 0, 1));
        const double x = 2.0 * u.x() - 1.0, y = 2.0 * u.y() - 1.0;
        const double pi = 3.14159265358979323846;
        double r, theta;
        if (std::abs(x) > std::abs(y)) {
            r = x;
            theta = 0.25 * pi * (y / x);
        } else {
            r = y;
            theta = 0.5 * pi - 0.25 * pi * (x / y);
        }
        const Vec2f d = sample_uniform_disk_concentric(u);
        EXPECT_NEAR(d.x(), r * std::cos(theta), 3e-7) << i;
        EXPECT_NEAR(d.y(), r * std::sin(theta), 3e-7) << i;
    }
    EXPECT_EQ(sample_uniform_disk_concentric(Vec2f(0.5f, 0.5f)), Vec2f::Zero());
}

TEST(Warp, CosineHemisphereHistogramInCosTheta) {
    // cos θ of a cosine-distributed direction has density 2 t on [0, 1]: bin b holds
    // ((b+1)^2 - b^2) / B^2 of the samples.
    const int bins = 16, n = 1 << 18;
    std::vector<int> h(bins, 0);
    for (int i = 0; i < n; ++i) {
        const Vec3f w =
            sample_cosine_hemisphere(Vec2f(sample_1d(5, uint32_t(i), 0, 0), sample_1d(5, uint32_t(i), 0, 1)));
        ASSERT_NEAR(w.norm(), 1.f, 1e-5f);
        ASSERT_GE(w.z(), 0.f);
        ++h[std::min(bins - 1, int(w.z() * bins))];
    }
    for (int b = 0; b < bins; ++b) {
        const double expected = n * double((b + 1) * (b + 1) - b * b) / (bins * bins);
        EXPECT_NEAR(h[b], expected, 5 * std::sqrt(expected)) << "bin " << b;
    }
}

TEST(Warp, CosineHemisphereBatchEqualsScalar) {
    // The tracer samples Lambertian vertices from the batch and every other use from the scalar
    // warp, so the two must give the same floats (a zero's sign aside: -0 == +0), on the
    // quadrant diagonals, the centre and the edges of [0,1)^2 included.
    std::vector<float> u0, u1;
    for (int i = 0; i < 4099; ++i) {  // not a multiple of the vector width: the scalar tail too
        u0.push_back(sample_1d(9, uint32_t(i), 0, 0));
        u1.push_back(sample_1d(9, uint32_t(i), 0, 1));
    }
    const float edges[] = {0.f, 0.25f, 0.5f, 0.75f, 0x1.fffffep-1f};
    for (float a : edges)
        for (float b : edges) {
            u0.push_back(a);
            u1.push_back(b);
        }
    const size_t n = u0.size();
    std::vector<float> x(n), y(n), z(n);
    sample_cosine_hemisphere_batch(u0.data(), u1.data(), x.data(), y.data(), z.data(), n);
    for (size_t i = 0; i < n; ++i) {
        const Vec3f w = sample_cosine_hemisphere(Vec2f(u0[i], u1[i]));
        ASSERT_EQ(x[i], w.x()) << i;
        ASSERT_EQ(y[i], w.y()) << i;
        ASSERT_EQ(z[i], w.z()) << i;
    }
}
