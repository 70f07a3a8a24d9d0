// Pearson chi-square goodness-of-fit of a direction sampler against its claimed density on the
// sphere (Nori warptest / Mitsuba chi2.py): bin samples in theta x phi, integrate the pdf over
// each cell numerically for the expected counts, pool cells expecting < 5, compare the
// statistic with the chi-square distribution. Samples that are not directions of the density
// (delta lobes, failed samples) fall in one extra cell expecting n (1 - ∫ pdf).
// Below it, the BSDF adapters shared by the BSDF tests: (a) chi-square, (b) weight == eval/pdf,
// (c) reciprocity, (d) Monte Carlo albedo, all on BSDFs built from Props through make_bsdf.
#pragma once
#include "core/bsdf.h"
#include "core/geometry.h"
#include "core/sampler.h"
#include "core/warp.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <bitset>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace lpt::test {

/// Deterministic uniform [0, 1) stream (splitmix64), so every run bins the same samples.
struct Rng {
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed) {}
    float next() {
        state += 0x9e3779b97f4a7c15ULL;
        return float(mix64(state) >> 40) * 0x1.0p-24f;
    }
    Vec2f next2() {
        float a = next();
        return Vec2f(a, next());
    }
};

/// Regularised upper incomplete gamma function Q(a, x) (series for x < a + 1, else Lentz's
/// continued fraction; Numerical Recipes 6.2).
inline double gamma_q(double a, double x) {
    if (x <= 0.0) return 1.0;
    double log_prefix = -x + a * std::log(x) - std::lgamma(a);
    if (x < a + 1.0) {
        double term = 1.0 / a, sum = term;
        for (int n = 1; n < 1000 && std::abs(term) > std::abs(sum) * 1e-15; ++n) {
            term *= x / (a + n);
            sum += term;
        }
        return std::max(0.0, 1.0 - sum * std::exp(log_prefix));
    }
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 1000; ++i) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        d = std::abs(d) < tiny ? tiny : d;
        c = b + an / c;
        c = std::abs(c) < tiny ? tiny : c;
        d = 1.0 / d;
        double delta = d * c;
        h *= delta;
        if (std::abs(delta - 1.0) < 1e-15) break;
    }
    return std::exp(log_prefix) * h;
}

/// Per-test significance that keeps the family-wise rate at `alpha` over `n_tests` (Sidak).
inline double sidak_significance(double alpha, int n_tests) { return 1.0 - std::pow(1.0 - alpha, 1.0 / n_tests); }

struct Chi2Result {
    bool passed = false;
    double statistic = 0.0, p_value = 0.0;
    int dof = 0;
    std::string summary;
};

inline Vec3f sphere_dir(double theta, double phi) {
    return Vec3f(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)),
                 float(std::cos(theta)));
}

/// Pearson's chi-square of observed against expected cell counts (cells of expected < 5 pooled);
/// cell n_cells holds the samples outside the density.
inline Chi2Result chi2_from_counts(const std::vector<double>& observed, const std::vector<double>& expected,
                                   int n_cells, int n_samples, double total, double significance) {
    Chi2Result r;
    std::ostringstream msg;
    msg << "integral of pdf = " << total << ", samples outside the density = " << observed[n_cells] << "/" << n_samples;
    std::vector<int> order(n_cells + 1);
    for (int i = 0; i <= n_cells; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) { return expected[a] < expected[b]; });
    double pool_obs = 0.0, pool_exp = 0.0;
    for (int i : order) {
        if (i < n_cells && expected[i] == 0.0 && observed[i] > 0.0) {
            msg << "; " << observed[i] << " samples in cell " << i << " of zero density";
            r.summary = msg.str();
            return r;
        }
        if (expected[i] < 5.0 || (pool_exp > 0.0 && pool_exp < 5.0)) {
            pool_obs += observed[i];
            pool_exp += expected[i];
        } else {
            r.statistic += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
            ++r.dof;
        }
    }
    if (pool_exp > 0.0) {
        r.statistic += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        ++r.dof;
    }
    r.dof -= 1;
    r.p_value = r.dof > 0 ? gamma_q(0.5 * r.dof, 0.5 * r.statistic) : 1.0;
    r.passed = r.p_value >= significance;
    msg << "; chi2 = " << r.statistic << ", dof = " << r.dof << ", p = " << r.p_value << " (needs >= " << significance
        << ")";
    r.summary = msg.str();
    return r;
}

/// sample(): the next direction, or nullopt for a sample outside the tested density.
/// pdf(w): solid-angle density of the tested part. Quadrature nodes lie strictly inside cells,
/// so density jumps at the horizon (a cell edge) are harmless.
template <class SampleFn, class PdfFn>
Chi2Result chi2_sphere_test(SampleFn&& sample, PdfFn&& pdf, int n_samples, double significance, int n_theta = 10,
                            int n_phi = 20, int min_sub = 4) {
    const int n_cells = n_theta * n_phi;
    std::vector<double> observed(n_cells + 1, 0.0), expected(n_cells + 1, 0.0);
    const double d_theta = kPi / n_theta, d_phi = 2.0 * kPi / n_phi;
    for (int i = 0; i < n_samples; ++i) {
        std::optional<Vec3f> w = sample();
        if (!w) {
            observed[n_cells] += 1.0;
            continue;
        }
        double theta = std::acos(std::clamp(double(w->z()) / w->norm(), -1.0, 1.0));
        double phi = std::atan2(double(w->y()), double(w->x()));
        if (phi < 0.0) phi += 2.0 * kPi;
        int t = std::min(n_theta - 1, int(theta / d_theta)), p = std::min(n_phi - 1, int(phi / d_phi));
        observed[t * n_phi + p] += 1.0;
    }
    // Composite 3-point Gauss-Legendre per cell, refined until two levels agree: sharp lobes
    // (low roughness, grazing angles) need far finer grids than the rest of the sphere.
    const double gx[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, gw[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    auto integrate = [&](int t, int p, int sub) {
        double sum = 0.0, ht = d_theta / sub, hp = d_phi / sub;
        for (int a = 0; a < sub; ++a)
            for (int ia = 0; ia < 3; ++ia) {
                double theta = t * d_theta + (a + 0.5 + 0.5 * gx[ia]) * ht;
                for (int b = 0; b < sub; ++b)
                    for (int ib = 0; ib < 3; ++ib) {
                        double phi = p * d_phi + (b + 0.5 + 0.5 * gx[ib]) * hp;
                        sum += gw[ia] * gw[ib] * std::sin(theta) * double(pdf(sphere_dir(theta, phi)));
                    }
            }
        return sum * 0.25 * ht * hp;
    };
    double total = 0.0;
    for (int t = 0; t < n_theta; ++t)
        for (int p = 0; p < n_phi; ++p) {
            int sub = min_sub;
            double cell = integrate(t, p, sub);
            while (sub < 128) {
                sub *= 2;
                double finer = integrate(t, p, sub);
                bool converged = std::abs(finer - cell) <= 2e-4 * std::abs(finer) + 1e-6;
                cell = finer;
                if (converged) break;
            }
            expected[t * n_phi + p] = cell * n_samples;
            total += cell;
        }
    expected[n_cells] = std::max(0.0, 1.0 - total) * n_samples;

    return chi2_from_counts(observed, expected, n_cells, n_samples, total, significance);
}

// ---- BSDF adapters ------------------------------------------------------------------------

using Values = std::vector<std::pair<std::string, PropValue>>;  ///< Props values in order

inline Props props(const std::string& type, const Values& values = {}) {
    Props p;
    p.type = type;
    p.file = "test";
    for (const auto& [k, v] : values) p.values[k] = v;
    return p;
}
inline Eigen::Array3f rgb(float r, float g, float b) { return Eigen::Array3f(r, g, b); }

inline std::string describe(const Props& p) {
    std::ostringstream s;
    s << p.type;
    for (const auto& [k, v] : p.values) {
        s << " " << k << "=";
        if (auto* f = std::get_if<float>(&v)) s << *f;
        else if (auto* str = std::get_if<std::string>(&v)) s << *str;
        else if (auto* c = std::get_if<Eigen::Array3f>(&v)) s << "(" << c->transpose() << ")";
        else if (auto* b = std::get_if<bool>(&v)) s << *b;
        else if (auto* child = std::get_if<std::shared_ptr<Props>>(&v)) s << "{" << describe(**child) << "}";
    }
    return s.str();
}

inline Vec3f dir(float cos_t, float phi) {
    float s = std::sqrt(std::max(0.f, 1.f - cos_t * cos_t));
    return Vec3f(s * std::cos(phi), s * std::sin(phi), cos_t);
}
inline BSDFContext context(TransportMode mode) {
    BSDFContext ctx;
    ctx.mode = mode;
    return ctx;
}

// (a) sample() against pdf() over the non-delta part; delta and failed samples share one cell.
inline void expect_chi2(const Props& p, const std::vector<Vec3f>& wis, double significance, int n = 100000) {
    auto bsdf = make_bsdf<3>(p);
    BSDFContext ctx;
    uint64_t seed = 1;
    for (const Vec3f& wi : wis) {
        Rng rng(seed++);
        auto sample = [&]() -> std::optional<Vec3f> {
            float u1 = rng.next();
            BSDFSample<3> bs = bsdf->sample(ctx, wi, u1, rng.next2());
            if (!bs.valid() || (bs.lobe & kDelta)) return std::nullopt;
            return bs.wo;
        };
        auto pdf = [&](const Vec3f& wo) { return bsdf->pdf(ctx, wi, wo); };
        Chi2Result r = chi2_sphere_test(sample, pdf, n, significance);
        EXPECT_TRUE(r.passed) << describe(p) << ", wi = (" << wi.transpose() << "): " << r.summary;
    }
}

// (b) weight == eval / pdf and pdf == pdf() for non-delta samples; lobe and eta bookkeeping.
inline void expect_weights(const Props& p, const std::vector<Vec3f>& wis, TransportMode mode, int n = 20000) {
    auto bsdf = make_bsdf<3>(p);
    BSDFContext ctx = context(mode);
    Rng rng(7);
    int failures = 0, checked = 0;
    std::string first;
    for (const Vec3f& wi : wis)
        for (int i = 0; i < n; ++i) {
            float u1 = rng.next();
            BSDFSample<3> bs = bsdf->sample(ctx, wi, u1, rng.next2());
            if (!bs.valid()) continue;
            std::ostringstream why;
            bool transmit = bs.lobe & kTransmission;
            if (std::bitset<32>(bs.lobe).count() != 1 || (bs.lobe & ~bsdf->flags())) why << "bad lobe " << bs.lobe;
            if (std::abs(bs.wo.norm() - 1.f) > 1e-4f) why << "wo not unit";
            if (transmit != (bs.wo.z() * wi.z() < 0.f)) why << "wo on the wrong side";
            if (transmit == (bs.eta == 1.f)) why << "eta " << bs.eta << " for lobe " << bs.lobe;
            if (!(bs.lobe & kDelta)) {
                ++checked;
                float pdf = bsdf->pdf(ctx, wi, bs.wo);
                Spectrum<3> expect = bsdf->eval(ctx, wi, bs.wo) / bs.pdf;
                if (std::abs(pdf - bs.pdf) > 1e-3f * bs.pdf) why << "pdf " << bs.pdf << " vs pdf() " << pdf;
                if ((bs.weight - expect).abs().maxCoeff() > 1e-3f * expect.abs().maxCoeff() + 1e-6f)
                    why << "weight " << bs.weight.transpose() << " vs eval/pdf " << expect.transpose();
            }
            if (!why.str().empty() && failures++ == 0)
                first = "wi = (" + std::to_string(wi.x()) + ", " + std::to_string(wi.y()) + ", " +
                        std::to_string(wi.z()) + "): " + why.str();
        }
    EXPECT_EQ(failures, 0) << describe(p) << ", first: " << first;
    if (!bsdf->is_delta()) {
        EXPECT_GT(checked, 0) << describe(p);
    }
}

// (c) f(wi,wo) vs f(wo,wi); across an interface f/eta_o^2 is symmetric in Importance mode and
// f/eta_i^2 in Radiance mode. `eta` = int_ior / ext_ior (1 for reflection-only BSDFs).
inline void expect_reciprocal(const Props& p, bool both_sides, float eta = 1.f, int n = 4000) {
    auto bsdf = make_bsdf<3>(p);
    for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance}) {
        BSDFContext ctx = context(mode);
        Rng rng(11);
        int failures = 0, nonzero = 0;
        std::string first;
        for (int i = 0; i < n; ++i) {
            Vec3f wi = sample_uniform_sphere(rng.next2()), wo = sample_uniform_sphere(rng.next2());
            if (!both_sides) wi.z() = std::abs(wi.z()), wo.z() = std::abs(wo.z());
            if (std::abs(wi.z()) < 0.02f || std::abs(wo.z()) < 0.02f) continue;
            Spectrum<3> f1 = bsdf->eval(ctx, wi, wo) / std::abs(wo.z());
            Spectrum<3> f2 = bsdf->eval(ctx, wo, wi) / std::abs(wi.z());
            float n_i = wi.z() > 0.f ? 1.f : eta, n_o = wo.z() > 0.f ? 1.f : eta;
            float ratio = mode == TransportMode::Importance ? (n_o * n_o) / (n_i * n_i) : (n_i * n_i) / (n_o * n_o);
            Spectrum<3> g = f2 * ratio;
            nonzero += f1.abs().maxCoeff() > 0.f;
            float scale = std::max(f1.abs().maxCoeff(), g.abs().maxCoeff());
            if ((f1 - g).abs().maxCoeff() > 2e-3f * scale + 1e-6f && failures++ == 0)
                first = std::to_string(f1[0]) + " vs " + std::to_string(g[0]) + " at wi.z = " + std::to_string(wi.z()) +
                        ", wo.z = " + std::to_string(wo.z());
        }
        EXPECT_EQ(failures, 0) << describe(p) << (mode == TransportMode::Radiance ? " radiance" : " importance")
                               << ", first: " << first;
        EXPECT_GT(nonzero, n / 10) << describe(p);
    }
}

// (d) Monte Carlo albedo: mean of the sample weights (0 for failed samples), with its SE.
struct Albedo {
    double mean = 0.0, se = 0.0;
};
/// Mean and standard error of f(u1, u2) over n draws of Rng(seed) (u1 drawn first).
template <typename F>
Albedo sample_mean(uint64_t seed, int n, F&& f) {
    Rng rng(seed);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; ++i) {
        float u1 = rng.next();
        double w = f(u1, rng.next2());
        sum += w;
        sum2 += w * w;
    }
    Albedo a;
    a.mean = sum / n;
    a.se = std::sqrt(std::max(0.0, sum2 / n - a.mean * a.mean) / (n - 1));
    return a;
}
/// A sample's mean weight, 0 for a failed sample.
inline double sample_weight_mean(const BSDF<3>& bsdf, const BSDFContext& ctx, const Vec3f& wi, float u1,
                                 const Vec2f& u2) {
    BSDFSample<3> bs = bsdf.sample(ctx, wi, u1, u2);
    return bs.valid() ? double(bs.weight.mean()) : 0.0;
}
inline Albedo albedo(const BSDF<3>& bsdf, const Vec3f& wi, TransportMode mode, int n = 100000) {
    const BSDFContext ctx = context(mode);
    return sample_mean(3, n, [&](float u1, const Vec2f& u2) { return sample_weight_mean(bsdf, ctx, wi, u1, u2); });
}
inline void expect_energy(const Props& p, const std::vector<Vec3f>& wis, TransportMode mode, double lower = 0.0) {
    auto bsdf = make_bsdf<3>(p);
    for (const Vec3f& wi : wis) {
        Albedo a = albedo(*bsdf, wi, mode);
        EXPECT_LE(a.mean, 1.0 + 3.0 * a.se + 1e-5) << describe(p) << ", cos wi = " << wi.z();
        EXPECT_GE(a.mean, lower - 3.0 * a.se) << describe(p) << ", cos wi = " << wi.z();
    }
}

}  // namespace lpt::test
