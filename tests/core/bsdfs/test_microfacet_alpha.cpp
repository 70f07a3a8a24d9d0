// Roughness alpha as a fit parameter (docs/bsdfs.md (37)-(43)), the microfacet distributions:
// the analytic ∂D/∂α, ∂G1/∂α of Beckmann and GGX against central differences of double-precision
// twins, finiteness at degenerate directions, set_alpha's clamp. Deterministic point sets
// (sample_1d), so thresholds are real. The plugins' gradients: test_bsdf_alpha.cpp.
#include "core/bsdf.h"
#include "core/bsdfs/microfacet.h"
#include "core/sampler.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace lpt;

namespace {

constexpr MicrofacetType kTypes[] = {MicrofacetType::Beckmann, MicrofacetType::GGX};
const char* name(MicrofacetType t) { return t == MicrofacetType::GGX ? "ggx" : "beckmann"; }

Vec3f sphere(float u, float v) {
    float z = 2.f * u - 1.f, r = std::sqrt(std::max(0.f, 1.f - z * z)), phi = 2.f * kPi * v;
    return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
}

// Double-precision twins of D (5)/(6) and G1 (7), the same expressions as microfacet.cpp. The
// float functions cannot be differenced at h = 1e-4 α: one float rounding of D (6e-8 |D|)
// divided by 2h is ~3e-4 |D|/α, the size of the tolerance itself. ReferenceMatchesFloat
// checks that these twins are the functions the code computes.
double ref_D(MicrofacetType type, double alpha, const Vec3f& mf) {
    Eigen::Vector3d m = mf.cast<double>();
    if (m.z() <= 0.0) return 0.0;
    double c2 = m.z() * m.z(), t2 = (m.x() * m.x() + m.y() * m.y()) / c2, a2 = alpha * alpha;
    if (type == MicrofacetType::Beckmann) return std::exp(-t2 / a2) / (M_PI * a2 * c2 * c2);
    double b = 1.0 + t2 / a2;
    return 1.0 / (M_PI * a2 * c2 * c2 * b * b);
}

double ref_G1(MicrofacetType type, double alpha, const Vec3f& vf, const Vec3f& mf) {
    if (vf.dot(mf) * vf.z() <= 0.f) return 0.0;  // the same float test as G1
    Eigen::Vector3d v = vf.cast<double>();
    double xy2 = v.x() * v.x() + v.y() * v.y();
    if (xy2 == 0.0) return 1.0;
    double at2 = alpha * alpha * xy2 / (v.z() * v.z());
    if (type == MicrofacetType::GGX) return 2.0 / (1.0 + std::sqrt(1.0 + at2));
    double a = 1.0 / std::sqrt(at2);
    double lambda = 0.5 * (std::exp(-a * a) / (a * std::sqrt(M_PI)) - std::erfc(a));
    return 1.0 / (1.0 + std::max(0.0, lambda));
}

// Microfacet normals: half from the sampler (where D matters), half uniform over the upper
// hemisphere (tails); directions v uniform over the sphere (both sides, both signs of v·m).
struct Pair {
    Vec3f v, m;
};
std::vector<Pair> microfacet_points(const MicrofacetDistribution& d, int n) {
    std::vector<Pair> out;
    for (uint32_t i = 0; i < uint32_t(n); ++i) {
        Vec3f v = sphere(sample_1d(11, i, 0, 0), sample_1d(11, i, 0, 1));
        Vec2f u(sample_1d(11, i, 0, 2), sample_1d(11, i, 0, 3));
        Vec3f m = i % 2 ? d.sample(v.z() < 0.f ? Vec3f(-v) : v, u) : sphere(0.5f + 0.5f * u.x(), u.y());
        out.push_back({v, m});
    }
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST(MicrofacetAlpha, ReferenceMatchesFloat) {
    for (MicrofacetType type : kTypes)
        for (float alpha : {0.05f, 0.2f, 0.5f, 0.9f}) {
            MicrofacetDistribution d(type, alpha);
            for (const Pair& p : microfacet_points(d, 2048)) {
                double D = ref_D(type, alpha, p.m), G1 = ref_G1(type, alpha, p.v, p.m);
                EXPECT_NEAR(d.D(p.m), D, 1e-5 * D + 1e-30) << name(type) << " " << alpha;
                EXPECT_NEAR(d.G1(p.v, p.m), G1, 1e-6) << name(type) << " " << alpha;
            }
        }
}

TEST(MicrofacetAlpha, DerivativesMatchCentralDifferences) {
    // h = 1e-4 α in double: truncation h² f'''/6 is < 1e-4 relative even 70 e-folds down the
    // Beckmann tail (f'''/f' ~ (2 tan²θ/α²)²/α², D still a normal float), rounding ~1e-12. The
    // analytic derivative is float: relative error ~1e-6, but near its sign change (tan θm = α
    // for D) its absolute error is a few eps · D/α, hence the floor 1e-5 · value/α.
    const double rel = 1e-3;
    for (MicrofacetType type : kTypes)
        for (float alpha : {0.05f, 0.1f, 0.2f, 0.35f, 0.5f, 0.7f, 0.9f}) {
            MicrofacetDistribution d(type, alpha);
            const double a = alpha, h = 1e-4 * a;
            int nD = 0, nG = 0;
            for (const Pair& p : microfacet_points(d, 4096)) {
                const Vec3f& m = p.m;
                if (d.D(m) > 1e-30f) {  // a normal float with digits to spare
                    double fd = (ref_D(type, a + h, m) - ref_D(type, a - h, m)) / (2.0 * h);
                    double g = d.dD_dalpha(m), floor = 1e-5 * ref_D(type, a, m) / a;
                    EXPECT_LE(std::abs(g - fd), rel * std::abs(fd) + floor)
                        << name(type) << " α " << alpha << " m " << m.transpose();
                    nD += std::abs(fd) > 1e-2 * ref_D(type, a, m) / a;
                }
                double fd = (ref_G1(type, a + h, p.v, m) - ref_G1(type, a - h, p.v, m)) / (2.0 * h);
                double g = d.dG1_dalpha(p.v, m), floor = 1e-5 * ref_G1(type, a, p.v, m) / a;
                EXPECT_LE(std::abs(g - fd), rel * std::abs(fd) + floor)
                    << name(type) << " α " << alpha << " v " << p.v.transpose();
                nG += std::abs(fd) > 1e-2 * ref_G1(type, a, p.v, m) / a;
                // G = G1 G1: the product rule of dG_dalpha.
                Vec3f wo = sphere(0.5f + 0.5f * std::abs(p.v.x()), 0.5f + 0.5f * p.v.y());
                double fdG = (ref_G1(type, a + h, p.v, m) * ref_G1(type, a + h, wo, m) -
                              ref_G1(type, a - h, p.v, m) * ref_G1(type, a - h, wo, m)) /
                             (2.0 * h);
                double gG = d.dG_dalpha(p.v, wo, m);
                EXPECT_LE(std::abs(gG - fdG), rel * std::abs(fdG) + 1e-5 * d.G(p.v, wo, m) / a)
                    << name(type) << " α " << alpha;
                // D G: the product rule of dDG_dalpha, the factor every rough plugin uses.
                if (d.D(m) > 1e-30f) {
                    auto DG = [&](double al) {
                        return ref_D(type, al, m) * ref_G1(type, al, p.v, m) * ref_G1(type, al, wo, m);
                    };
                    double fdDG = (DG(a + h) - DG(a - h)) / (2.0 * h), gDG = d.dDG_dalpha(p.v, wo, m);
                    EXPECT_LE(std::abs(gDG - fdDG), rel * std::abs(fdDG) + 1e-5 * DG(a) / a)
                        << name(type) << " α " << alpha;
                }
            }
            EXPECT_GT(nD, 1000) << name(type) << " α " << alpha;  // non-trivial derivatives were compared
            EXPECT_GT(nG, 200) << name(type) << " α " << alpha;
        }
}

TEST(MicrofacetAlpha, FiniteAtDegenerateDirections) {
    // Grazing directions whose tan² overflows or whose cos⁴ underflows: values as D/G1, and
    // finite derivatives (no 0 · inf).
    const std::vector<Vec3f> dirs = {Vec3f(1.f, 0.f, 1e-30f), Vec3f(0.6f, 0.8f, 1e-21f), Vec3f(1.f, 0.f, 1e-12f),
                                     Vec3f(0.f, 0.f, 1.f),    Vec3f(0.f, 0.f, -1.f),     Vec3f(1.f, 0.f, 0.f)};
    for (MicrofacetType type : kTypes)
        for (float alpha : {1e-4f, 0.3f, 3.f})
            for (const Vec3f& v : dirs)
                for (const Vec3f& m : dirs) {
                    MicrofacetDistribution d(type, alpha);
                    auto [D, dD] = d.D_dalpha(m);
                    auto [G1, dG1] = d.G1_dalpha(v, m);
                    EXPECT_TRUE(D == d.D(m) || (std::isnan(D) && std::isnan(d.D(m)))) << name(type);
                    EXPECT_EQ(G1, d.G1(v, m)) << name(type);
                    if (std::isfinite(D)) {
                        EXPECT_TRUE(std::isfinite(dD)) << name(type) << " " << alpha << " m " << m.transpose();
                    }
                    EXPECT_TRUE(std::isfinite(dG1)) << name(type) << " " << alpha << " v " << v.transpose();
                }
}

TEST(MicrofacetAlpha, SetAlphaClampsLikeTheConstructor) {
    for (MicrofacetType type : kTypes) {
        MicrofacetDistribution d(type, 0.3f);
        d.set_alpha(0.45f);
        EXPECT_EQ(d.alpha(), 0.45f);
        d.set_alpha(1e-6f);
        EXPECT_EQ(d.alpha(), MicrofacetDistribution::kMinAlpha);
        EXPECT_EQ(d.alpha(), MicrofacetDistribution(type, 0.f).alpha());
        d.set_alpha(-1.f);
        EXPECT_EQ(d.alpha(), 1e-4f);
    }
}
