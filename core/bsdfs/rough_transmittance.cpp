// Rough-coating transmittance tables: direct quadrature (docs/bsdfs.md (26), (42)) and the
// cached log-α Hermite interpolation of it (46).
#include "core/bsdfs/rough_transmittance.h"
#include "core/bsdfs/fresnel.h"
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>

namespace lpt {
namespace {

constexpr int K = 64;                // quadrature grid K×K per table entry
constexpr double kNodeStep = 0.125;  // Δs between nodes in s = ln(α / kMinAlpha)

// Unclamped table values (a lobe's albedo at μ_j) and their ∂/∂α at one α: the raw node data.
struct RawTables {
    std::array<double, kTransmittanceRes> t{}, dt{};
};

// The lobe's direction for microfacet m and its Fresnel factor: reflection with R, refraction
// with 1 − R (Mitsuba's eval_reflectance / eval_transmittance integrands), the Fresnel-free
// reflection with 1; false where the lobe has no direction on its side (below the surface for
// reflection, total internal reflection or back above it for refraction).
bool lobe_direction(const Vec3f& wi, const Vec3f& m, float eta, CoatingLobe lobe, Vec3f& wo, double& fresnel) {
    const FresnelDielectric f = fresnel_dielectric(wi.dot(m), eta);
    if (lobe != CoatingLobe::Transmission) {
        wo = reflect(wi, m);
        fresnel = lobe == CoatingLobe::Reflection ? double(f.R) : 1.0;
        return wo.z() > 0.f;
    }
    if (f.cos_t == 0.f) return false;
    wo = refract(wi, m, f.cos_t, f.eta_ti);
    fresnel = 1.0 - double(f.R);
    return wo.z() < 0.f;
}

// The sampler's first coordinate u1 = 1 − (1 − v)² for a midpoint grid in v, and du1/dv. Both
// samplers put the steepest microfacets at u1 → 1, where reflection sends wo below the horizon:
// a discontinuity that a plain grid in u1 never reaches for GGX, whose tail is heavy (a fraction
// α²/(1 + α²) of its normals tilt beyond 45° at normal incidence; docs/bsdfs.md (26) has what
// that cost). For Beckmann, d ln D/dα also grows like −ln(1 − u1) toward u1 = 1, and
// (1 − v) ln(1 − v) → 0 smooths it.
struct TailNode {
    double u1, jacobian;
};
TailNode tail_node(int a) {
    const double v = (a + 0.5) / K;
    return {1.0 - (1.0 - v) * (1.0 - v), 2.0 * (1.0 - v)};
}

// The lobe's albedo at incidence wi, ∫ F_lobe D G |wi·m| / μ dm (reflection: A(μ), refraction:
// T(μ); docs/bsdfs.md (26)), by a midpoint grid over the microfacet sampler's unit square with
// u1 from tail_node; sample_weight is D G |wi·m| / (μ p(m)) for either side.
double lobe_albedo(const MicrofacetDistribution& distr, float eta, const Vec3f& wi, CoatingLobe lobe) {
    double sum = 0.0;
    for (int a = 0; a < K; ++a) {
        const TailNode n = tail_node(a);
        for (int b = 0; b < K; ++b) {
            Vec3f m = distr.sample(wi, Vec2f(float(n.u1), (b + 0.5f) / K)), wo;
            double fresnel;
            if (!lobe_direction(wi, m, eta, lobe, wo, fresnel)) continue;
            sum += n.jacobian * fresnel * distr.sample_weight(wi, wo, m);
        }
    }
    return sum / (K * K);
}

// ∂A/∂α at incidence wi (docs/bsdfs.md (42)): ∫ R(wi·h) ∂(D G)/∂α / (4 mu) dωo over the
// upper hemisphere, with the directions held fixed (only the integrand moves with α),
// importance-sampled by the microfacet sampler at the current α over the grid of tail_node:
// E_u[R (∂D G + D ∂G)(wo·m) / (mu p(m | wi))], p(m | wi) from (8)/(9), the reflection
// Jacobian (10) turning p(m) into p(wo).
double dreflectance_dalpha(const MicrofacetDistribution& distr, float eta, const Vec3f& wi) {
    double mu = wi.z(), sum = 0.0;
    for (int a = 0; a < K; ++a) {
        const auto [u1, jac] = tail_node(a);
        for (int b = 0; b < K; ++b) {
            Vec3f m = distr.sample(wi, Vec2f(float(u1), (b + 0.5f) / K));
            Vec3f wo = reflect(wi, m);
            float wo_m = wo.dot(m);
            if (wo.z() <= 0.f || wo_m <= 0.f) continue;
            double pm = distr.pdf(wi, m);
            if (!(pm > 0.0)) continue;
            double dDG = distr.dDG_dalpha(wi, wo, m);
            sum += jac * fresnel_dielectric(wi.dot(m), eta).R * dDG * wo_m / (mu * pm);
        }
    }
    return sum / (K * K);
}

// Step in ln α of the transmittance's node slopes (central differences, O(δ²) ~ 1e-4 relative).
constexpr double kSlopeStep = 0.01;

RawTables raw_tables(MicrofacetType type, float eta, float alpha, CoatingLobe lobe) {
    MicrofacetDistribution distr(type, alpha);
    // The transmittance's ∂/∂α comes from central differences of its own quadrature in ln α
    // (the sample points move smoothly with α). The derivative integral, used for A, converges
    // far too slowly for T: d ln D/dα grows like tan²θm/α² on tilted microfacets, which
    // reflection sends below the horizon but refraction keeps (on plain grids in u, 32×32: 45 %
    // off T̄'s slope for Beckmann at α = 0.1, 128×128: 3.5 %). At the α floor the difference is
    // one-sided.
    const double up = std::exp(kSlopeStep),
                 down = std::max(std::exp(-kSlopeStep), MicrofacetDistribution::kMinAlpha / double(alpha));
    MicrofacetDistribution distr_up(type, float(alpha * up)), distr_down(type, float(alpha * down));
    RawTables r;
    for (int j = 0; j < kTransmittanceRes; ++j) {
        float mu = std::max(1e-6f, float(j) / (kTransmittanceRes - 1));
        Vec3f wi(std::sqrt(std::max(0.f, 1.f - mu * mu)), 0.f, mu);
        r.t[j] = double(float(lobe_albedo(distr, eta, wi, lobe)));
        if (lobe == CoatingLobe::Reflection) r.dt[j] = dreflectance_dalpha(distr, eta, wi);
        else
            r.dt[j] = (lobe_albedo(distr_up, eta, wi, lobe) - lobe_albedo(distr_down, eta, wi, lobe)) /
                      (double(alpha) * (up - down));
    }
    return r;
}

// Exact ∫ (linear segment) 2 mu dmu of a table, per segment [m0, m1] with values t0, t1.
double mean_cosine_weighted(const std::array<float, kTransmittanceRes>& table) {
    double total = 0.0, h = 1.0 / (kTransmittanceRes - 1);
    for (int j = 0; j + 1 < kTransmittanceRes; ++j) {
        double m0 = j * h, m1 = m0 + h, t0 = table[j], t1 = table[j + 1];
        double slope = (t1 - t0) / h;
        double c = t0 - slope * m0;  // t = c + slope * mu
        total += c * (m1 * m1 - m0 * m0) + slope * 2.0 / 3.0 * (m1 * m1 * m1 - m0 * m0 * m0);
    }
    return total;
}

// Clamps t to [0, 1] (a clamped entry is locally constant in α) and integrates T̄, ∂T̄/∂α.
TransmittanceTable finish(const std::array<double, kTransmittanceRes>& t,
                          const std::array<double, kTransmittanceRes>& dt) {
    TransmittanceTable out;
    for (int j = 0; j < kTransmittanceRes; ++j) {
        float tf = float(t[j]);
        out.t[j] = std::clamp(tf, 0.f, 1.f);
        out.dt[j] = tf == out.t[j] ? float(dt[j]) : 0.f;
    }
    out.mean = float(mean_cosine_weighted(out.t));
    out.dmean = float(mean_cosine_weighted(out.dt));
    return out;
}

// A node: raw t and its slope in s = ln α, m = α ∂t/∂α, at α_k = kMinAlpha exp(k Δs).
struct Node {
    std::array<double, kTransmittanceRes> t{}, dt_ds{};
};

std::mutex g_mutex;
std::map<std::tuple<int, int, float, int>, std::unique_ptr<const Node>> g_nodes;

const Node& node(MicrofacetType type, float eta, CoatingLobe lobe, int k) {
    std::lock_guard<std::mutex> lock(g_mutex);
    auto& slot = g_nodes[{int(type), int(lobe), eta, k}];
    if (!slot) {
        float alpha_k = float(MicrofacetDistribution::kMinAlpha * std::exp(k * kNodeStep));
        RawTables r = raw_tables(type, eta, alpha_k, lobe);
        auto n = std::make_unique<Node>();
        for (int j = 0; j < kTransmittanceRes; ++j) n->t[j] = r.t[j], n->dt_ds[j] = double(alpha_k) * r.dt[j];
        slot = std::move(n);
    }
    return *slot;
}

}  // namespace

TransmittanceTable rough_lobe_table_direct(MicrofacetType type, float eta, float alpha, CoatingLobe lobe) {
    RawTables r = raw_tables(type, eta, std::max(alpha, MicrofacetDistribution::kMinAlpha), lobe);
    return finish(r.t, r.dt);
}

TransmittanceTable rough_lobe_table(MicrofacetType type, float eta, float alpha, CoatingLobe lobe) {
    // docs/bsdfs.md (46): cubic Hermite in s over [s_k, s_k+1], x = (s − s_k)/Δs.
    double s = std::log(std::max(double(alpha), double(MicrofacetDistribution::kMinAlpha)) /
                        MicrofacetDistribution::kMinAlpha) /
               kNodeStep;
    int k = int(std::floor(s));
    double x = s - k, x2 = x * x, x3 = x2 * x;
    const Node& a = node(type, eta, lobe, k);
    const Node& b = node(type, eta, lobe, k + 1);
    double h00 = 2 * x3 - 3 * x2 + 1, h10 = x3 - 2 * x2 + x, h01 = -2 * x3 + 3 * x2, h11 = x3 - x2;
    double d00 = 6 * x2 - 6 * x, d10 = 3 * x2 - 4 * x + 1, d01 = -6 * x2 + 6 * x, d11 = 3 * x2 - 2 * x;
    double ds_dalpha = 1.0 / double(alpha);  // ∂(ln α)/∂α; the 1/Δs of x is applied per term
    std::array<double, kTransmittanceRes> t, dt;
    for (int j = 0; j < kTransmittanceRes; ++j) {
        t[j] = h00 * a.t[j] + kNodeStep * (h10 * a.dt_ds[j] + h11 * b.dt_ds[j]) + h01 * b.t[j];
        dt[j] = ((d00 * a.t[j] + d01 * b.t[j]) / kNodeStep + d10 * a.dt_ds[j] + d11 * b.dt_ds[j]) * ds_dalpha;
    }
    return finish(t, dt);
}

size_t rough_transmittance_nodes_built() {
    std::lock_guard<std::mutex> lock(g_mutex);
    return g_nodes.size();
}

}  // namespace lpt
