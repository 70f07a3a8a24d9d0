// Roughplastic's cached transmittance tables (docs/bsdfs.md (46)): the log-α Hermite
// interpolation against the direct quadrature at the same α (values and derivatives), the
// cache building each node once, and concurrent callers seeing the serial result.
#include "core/bsdfs/rough_transmittance.h"
#include <gtest/gtest.h>
#include <cmath>
#include <thread>

using namespace lpt;

namespace {

constexpr MicrofacetType kTypes[] = {MicrofacetType::Beckmann, MicrofacetType::GGX};
const char* name(MicrofacetType t) { return t == MicrofacetType::GGX ? "ggx" : "beckmann"; }
constexpr double kStep = 0.125;  // Δs of rough_transmittance.cpp

float node_alpha(int k) { return float(MicrofacetDistribution::kMinAlpha * std::exp(k * kStep)); }
int node_index(float alpha) { return int(std::floor(std::log(alpha / MicrofacetDistribution::kMinAlpha) / kStep)); }

float max_abs(const std::array<float, kTransmittanceRes>& a) {
    float m = 0.f;
    for (float v : a) m = std::max(m, std::abs(v));
    return m;
}

}  // namespace

TEST(RoughTransmittance, NodesReproduceTheDirectQuadrature) {
    // At a node the spline passes through the node's own quadrature with its slope.
    for (MicrofacetType type : kTypes)
        for (CoatingLobe lobe : {CoatingLobe::Transmission, CoatingLobe::Reflection})
            for (int k : {40, 55, 64, 72}) {
                float alpha = node_alpha(k);
                TransmittanceTable c = rough_lobe_table(type, 1.49f, alpha, lobe),
                                   d = rough_lobe_table_direct(type, 1.49f, alpha, lobe);
                const float dscale = max_abs(d.dt);
                for (int j = 0; j < kTransmittanceRes; ++j) {
                    EXPECT_NEAR(c.t[j], d.t[j], 1e-6f) << name(type) << " α " << alpha << " j " << j;
                    EXPECT_NEAR(c.dt[j], d.dt[j], 1e-5f * dscale) << name(type) << " α " << alpha << " j " << j;
                }
                EXPECT_NEAR(c.mean, d.mean, 1e-6f);
                EXPECT_NEAR(c.dmean, d.dmean, 1e-5f * dscale);
            }
}

TEST(RoughTransmittance, BetweenNodesWithinQuadratureAccuracy) {
    // Between nodes the spline is compared with a fresh quadrature at that α. They differ by
    // the quadrature's own α-wobble (its sample points move with α; A's node slopes come from a
    // different quadrature, of the exact ∂A/∂α integral, T's from central differences of its
    // own) plus the spline's O(Δs⁴) truncation. Measured maxima for A (η = 1.49, three points per interval):
    // |Δt| <= 3.0e-4 (the table's own accuracy is ~1e-3); |Δ∂t/∂α| <= 4.3e-2 of the table's
    // largest |∂t/∂α| for α >= 0.05, 1.4e-1 for GGX at α = 0.01 (8e-2 with a 64×64
    // quadrature: it is the quadrature, not the spline); |ΔT̄| <= 5e-5, |Δ∂T̄/∂α| <= 1.1e-2.
    // A wrong spline derivative (a missing 1/Δs or 1/α) is off by 100% or more.
    for (MicrofacetType type : kTypes)
        for (CoatingLobe lobe : {CoatingLobe::Transmission, CoatingLobe::Reflection})
            for (float a0 : {0.01f, 0.05f, 0.1f, 0.3f, 0.7f, 1.3f})
                for (double x : {0.25, 0.5, 0.75}) {
                    int k = node_index(a0);
                    float alpha = float(MicrofacetDistribution::kMinAlpha * std::exp((k + x) * kStep));
                    TransmittanceTable c = rough_lobe_table(type, 1.49f, alpha, lobe),
                                       d = rough_lobe_table_direct(type, 1.49f, alpha, lobe);
                    const float dscale = max_abs(d.dt), dbound = (a0 < 0.05f ? 0.2f : 6e-2f) * dscale;
                    ASSERT_GT(dscale, 0.f);
                    for (int j = 0; j < kTransmittanceRes; ++j) {
                        EXPECT_NEAR(c.t[j], d.t[j], 5e-4f) << name(type) << " α " << alpha << " j " << j;
                        EXPECT_NEAR(c.dt[j], d.dt[j], dbound) << name(type) << " α " << alpha << " j " << j;
                    }
                    EXPECT_NEAR(c.mean, d.mean, 1e-4f) << name(type) << " α " << alpha;
                    EXPECT_NEAR(c.dmean, d.dmean, 2e-2f * dscale) << name(type) << " α " << alpha;
                }
}

TEST(RoughTransmittance, EachNodeIsBuiltOnce) {
    // An IOR no other test uses, so every node of this sweep is new to the process.
    const float eta = 1.3719f, lo = 0.1f, hi = 0.2f;
    for (MicrofacetType type : kTypes) {
        size_t before = rough_transmittance_nodes_built();
        for (int i = 0; i <= 1000; ++i) rough_transmittance(type, eta, lo + (hi - lo) * i / 1000.f);
        size_t expected = size_t(node_index(hi) + 1 - node_index(lo) + 1);
        EXPECT_EQ(rough_transmittance_nodes_built() - before, expected) << name(type);
        before = rough_transmittance_nodes_built();
        for (int i = 0; i <= 1000; ++i) rough_transmittance(type, eta, lo + (hi - lo) * i / 1000.f);
        EXPECT_EQ(rough_transmittance_nodes_built(), before) << name(type) << ": a repeated sweep rebuilt nodes";
    }
}

TEST(RoughTransmittance, ConcurrentCallersSeeTheSerialTables) {
    const float eta = 1.6123f;
    std::vector<float> alphas;
    for (int i = 0; i < 40; ++i) alphas.push_back(0.05f + 0.02f * i);
    std::vector<TransmittanceTable> par(alphas.size());
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&, t] {
            for (size_t i = t; i < alphas.size(); i += 4)
                par[i] = rough_transmittance(MicrofacetType::GGX, eta, alphas[i]);
        });
    for (auto& th : threads) th.join();
    for (size_t i = 0; i < alphas.size(); ++i) {
        TransmittanceTable s = rough_transmittance(MicrofacetType::GGX, eta, alphas[i]);
        EXPECT_EQ(s.t, par[i].t) << alphas[i];
        EXPECT_EQ(s.dt, par[i].dt) << alphas[i];
        EXPECT_EQ(s.mean, par[i].mean);
        EXPECT_EQ(s.dmean, par[i].dmean);
    }
}

namespace {

/// Smith G1 of a direction at polar angle θ (isotropic, the microfacet on its own side).
double smith_g1(MicrofacetType type, double alpha, double theta) {
    const double t = std::tan(theta);
    if (t == 0.0) return 1.0;
    if (type == MicrofacetType::GGX) return 2.0 / (1.0 + std::sqrt(1.0 + alpha * alpha * t * t));
    const double a = 1.0 / (alpha * t);
    return 2.0 / (1.0 + std::erf(a) + std::exp(-a * a) / (a * std::sqrt(M_PI)));
}

/// D(θm) cos θm, the normals' projected-area density (each integrates to 1 over the hemisphere).
double projected_density(MicrofacetType type, double alpha, double theta) {
    const double c = std::cos(theta), t2 = std::tan(theta) * std::tan(theta), a2 = alpha * alpha;
    const double d = type == MicrofacetType::GGX ? 1.0 / (M_PI * a2 * c * c * c * c * (1.0 + t2 / a2) * (1.0 + t2 / a2))
                                                 : std::exp(-t2 / a2) / (M_PI * a2 * c * c * c * c);
    return d * c;
}

}  // namespace

TEST(RoughTransmittance, NormalIncidenceMatchesAOneDimensionalIntegral) {
    // At μ = 1 a normal tilted by θm reflects wo at 2θm, so every lobe is a 1-D integral in θm:
    // Fresnel-free A(1) = ∫_0^{π/4} D cos θm G1(2θm) 2π sin θm dθm (beyond π/4 wo is below the
    // horizon). Written here with no sampler and no grid over the unit square, on a fine
    // midpoint rule in θm; it fails for GGX on a plain 32² grid in the sampler's u, which cannot
    // see where the heavy tail crosses the horizon (0.998 against 0.988 at α = 0.1).
    for (MicrofacetType type : kTypes)
        for (float alpha : {0.05f, 0.1f, 0.2f, 0.5f}) {
            const int n = 400000;
            const double h = 0.25 * M_PI / n;
            double exact = 0.0, mass = 0.0;
            for (int i = 0; i < n; ++i) {
                const double th = (i + 0.5) * h;
                const double w = projected_density(type, alpha, th) * 2.0 * M_PI * std::sin(th) * h;
                exact += w * smith_g1(type, alpha, 2.0 * th);
                mass += w;
            }
            // The normals below 45° in closed form: P(tan²θm < 1).
            const double a2 = double(alpha) * alpha;
            const double below = type == MicrofacetType::GGX ? 1.0 / (1.0 + a2) : 1.0 - std::exp(-1.0 / a2);
            ASSERT_NEAR(mass, below, 1e-6) << name(type) << " α " << alpha;
            const TransmittanceTable t = rough_lobe_table_direct(type, 1.5f, alpha, CoatingLobe::Glossy);
            EXPECT_NEAR(t.t[kTransmittanceRes - 1], exact, 5e-4) << name(type) << " α " << alpha;
        }
}
