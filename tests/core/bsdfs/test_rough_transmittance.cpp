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
