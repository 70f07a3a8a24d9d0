// Roughness alpha as a fit parameter (docs/bsdfs.md (37)-(43)), the rough plugins: every rough
// plugin's eval_grad_scalar against central differences of eval at fixed (wi, wo), per channel;
// weight_grad_scalar == eval_grad_scalar / pdf; set_scalar re-deriving everything cached from
// alpha; key handling. Deterministic point sets (sample_1d), so thresholds are real. The
// microfacet distributions' own derivatives: test_microfacet_alpha.cpp.
#include "core/bsdf.h"
#include "core/bsdfs/microfacet.h"
#include "core/sampler.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace lpt;

namespace {

Vec3f sphere(float u, float v) {
    float z = 2.f * u - 1.f, r = std::sqrt(std::max(0.f, 1.f - z * z)), phi = 2.f * kPi * v;
    return Vec3f(r * std::cos(phi), r * std::sin(phi), z);
}

std::shared_ptr<Props> props(const std::string& type, const std::string& distr = "", float alpha = 0.3f) {
    auto p = std::make_shared<Props>();
    p->type = type;
    p->file = "test";
    if (type.rfind("rough", 0) == 0) {
        p->values["alpha"] = alpha;
        p->values["distribution"] = distr;
    }
    return p;
}
std::shared_ptr<Props> twosided(std::shared_ptr<Props> nested) {
    auto p = props("twosided");
    p->values["bsdf"] = std::move(nested);
    return p;
}
Spectrum<16> ramp(float a, float b) {
    Spectrum<16> s;
    for (int c = 0; c < 16; ++c) s[c] = a + b * float(c) / 15.f;
    return s;
}

struct Case {
    std::string name;
    std::shared_ptr<Props> p;
    std::vector<std::pair<std::string, Spectrum<16>>> colours;  ///< set_spectral after construction
    TransportMode mode = TransportMode::Radiance;
};

// The rough plugins with both distributions, signed latent colours and per-channel Fresnel.
// Roughplastic appears split by lobe (the other colour zero): its specular lobe is exact, its
// diffuse lobe carries the table approximation (42), tested separately.
std::vector<Case> rough_cases(bool plastic_diffuse) {
    std::vector<Case> cases;
    const Spectrum<16> c1 = ramp(-0.4f, 1.3f), c2 = ramp(0.9f, -0.6f), zero = Spectrum<16>::Zero();
    const PropValue eta = Eigen::Array3f(0.2f, 0.9f, 1.1f), k = Eigen::Array3f(3.9f, 2.4f, 2.2f);
    for (const char* d : {"beckmann", "ggx"}) {
        std::string D = d;
        if (plastic_diffuse) {
            for (bool nonlinear : {false, true}) {
                auto p = props("roughplastic", D);
                p->values["nonlinear"] = nonlinear;
                cases.push_back(
                    {"roughplastic diffuse " + D + (nonlinear ? " nonlinear" : ""),
                     p,
                     {{"diffuse_reflectance", nonlinear ? ramp(-0.4f, 0.9f) : c1}, {"specular_reflectance", zero}}});
            }
            continue;
        }
        auto cond = props("roughconductor", D);
        cond->values["eta"] = eta, cond->values["k"] = k;
        cases.push_back({"roughconductor " + D, cond, {{"specular_reflectance", c1}}});
        cases.push_back({"twosided roughconductor " + D, twosided(cond), {{"specular_reflectance", c1}}});
        for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance})
            cases.push_back({"roughdielectric " + D + (mode == TransportMode::Radiance ? " radiance" : " importance"),
                             props("roughdielectric", D),
                             {{"specular_reflectance", c1}, {"specular_transmittance", c2}},
                             mode});
        cases.push_back({"roughplastic specular " + D,
                         props("roughplastic", D),
                         {{"specular_reflectance", c1}, {"diffuse_reflectance", zero}}});
    }
    return cases;
}

std::unique_ptr<BSDF<16>> build(const Case& cs) {
    auto bsdf = make_bsdf<16>(*cs.p);
    for (const auto& [key, v] : cs.colours) bsdf->set_spectral(key, v);
    return bsdf;
}

// (wi, wo) pairs: wi over both faces (one-sided plugins must give zero gradients below), wo
// alternately sampled by the BSDF at the current alpha (inside the lobe) and uniform on the
// sphere (tails, the other side).
std::vector<std::pair<Vec3f, Vec3f>> direction_pairs(const BSDF<16>& bsdf, uint64_t seed, int n) {
    std::vector<std::pair<Vec3f, Vec3f>> out;
    for (uint32_t i = 0; i < uint32_t(n); ++i) {
        float z = (i % 4 < 3 ? 1.f : -1.f) * (0.05f + 0.95f * sample_1d(seed, i, 0, 0));
        float r = std::sqrt(1.f - z * z), phi = 2.f * kPi * sample_1d(seed, i, 0, 1);
        Vec3f wi(r * std::cos(phi), r * std::sin(phi), z);
        Vec3f wo = sphere(sample_1d(seed, i, 0, 2), sample_1d(seed, i, 0, 3));
        if (i % 2) {
            BSDFSample<16> bs = bsdf.sample(BSDFContext{}, wi, sample_1d(seed, i, 0, 4),
                                            Vec2f(sample_1d(seed, i, 0, 5), sample_1d(seed, i, 0, 6)));
            if (bs.valid()) wo = bs.wo;
        }
        out.push_back({wi, wo});
    }
    return out;
}

// Central differences of eval in alpha with steps h and 2h, Richardson-extrapolated
// ((8 Δ_h − Δ_2h) / 12 h: truncation O(h⁴)), per channel, for every pair; also the analytic
// gradient and the value at alpha.
struct FdResult {
    std::vector<Spectrum<16>> grad, fd, value;
};
FdResult differences(BSDF<16>& bsdf, const BSDFContext& ctx, const std::vector<std::pair<Vec3f, Vec3f>>& pairs,
                     float alpha, float h) {
    FdResult r;
    const float as[4] = {alpha + 2.f * h, alpha + h, alpha - h, alpha - 2.f * h};
    std::vector<Spectrum<16>> e[4];
    for (int k = 0; k < 4; ++k) {
        bsdf.set_scalar("alpha", as[k]);
        for (const auto& [wi, wo] : pairs) e[k].push_back(bsdf.eval(ctx, wi, wo));
    }
    bsdf.set_scalar("alpha", alpha);
    const float s1 = as[1] - as[2], s2 = as[0] - as[3];  // the float steps actually taken
    for (size_t i = 0; i < pairs.size(); ++i) {
        r.grad.push_back(bsdf.eval_grad_scalar(ctx, pairs[i].first, pairs[i].second, 0));
        r.value.push_back(bsdf.eval(ctx, pairs[i].first, pairs[i].second));
        Spectrum<16> d1 = (e[1][i] - e[2][i]) / s1, d2 = (e[0][i] - e[3][i]) / s2;
        r.fd.push_back((4.f * d1 - d2) / 3.f);
    }
    return r;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
TEST(BSDFAlpha, EvalGradMatchesCentralDifferences) {
    // Exact derivatives (roughconductor, roughdielectric, roughplastic's specular lobe and its
    // diffuse lobe, whose t(μ) and ∂t/∂α tables are an interpolant and its exact derivative,
    // docs/bsdfs.md (46); twosided from both faces). eval is float, so its differences need a
    // larger step than (37)-(39)'s h = 1e-4 α: h = 2e-3 α with Richardson extrapolation.
    // Truncation ~h⁴ f⁽⁵⁾/30 < 2e-4 relative down to 70 e-folds of a Beckmann tail; rounding ~10 eps |f| / (2h) per
    // difference, ~3e-4 |f|/α after extrapolation. Hence the tolerance 1e-3 (|fd| + |f|/α): relative 1e-3 of the
    // derivative, floored at 1e-3 of the natural scale |f|/α where ∂f/∂α changes sign, and at 1e-30 absolute: far tails
    // where D or f is (nearly) subnormal carry no digits.
    const float rel = 1e-3f, tiny = 1e-30f;
    std::vector<Case> cases = rough_cases(false), diffuse = rough_cases(true);
    cases.insert(cases.end(), diffuse.begin(), diffuse.end());
    for (const Case& cs : cases)
        for (float alpha : {0.1f, 0.3f, 0.7f}) {
            auto bsdf = build(cs);
            bsdf->set_scalar("alpha", alpha);
            BSDFContext ctx;
            ctx.mode = cs.mode;
            auto pairs = direction_pairs(*bsdf, 21, 512);
            FdResult r = differences(*bsdf, ctx, pairs, alpha, 2e-3f * alpha);
            int nonzero = 0;
            for (size_t i = 0; i < pairs.size(); ++i) {
                for (int c = 0; c < 16; ++c) {
                    float g = r.grad[i][c], fd = r.fd[i][c], f = r.value[i][c];
                    float tol = rel * (std::abs(fd) + std::abs(f) / alpha) + tiny;
                    EXPECT_LE(std::abs(g - fd), tol)
                        << cs.name << " α " << alpha << " channel " << c << " wi " << pairs[i].first.transpose()
                        << " wo " << pairs[i].second.transpose();
                    nonzero += std::abs(fd) > 1e-2f * std::abs(f) / alpha && std::abs(fd) > 1e-20f;
                }
                EXPECT_TRUE(r.grad[i].isFinite().all()) << cs.name;
                if (pairs[i].first.z() < 0.f && cs.name.rfind("rough", 0) == 0 &&
                    cs.name.find("dielectric") == std::string::npos) {
                    EXPECT_TRUE((r.grad[i] == 0.f).all()) << cs.name << ": one-sided";
                }
            }
            EXPECT_GT(nonzero, 16 * 100) << cs.name << " α " << alpha;
        }
}

TEST(BSDFAlpha, RoughPlasticGradientIsTheSumOfItsLobes) {
    // The full plastic = specular-only + diffuse-only (eval is linear in the colours and the
    // tables are shared), so no cross term hides between the two tested halves.
    for (const char* d : {"beckmann", "ggx"})
        for (bool nonlinear : {false, true}) {
            auto p = props("roughplastic", d, 0.3f);
            p->values["nonlinear"] = nonlinear;
            const Spectrum<16> rd = ramp(-0.4f, 0.9f), rs = ramp(0.9f, -0.6f), zero = Spectrum<16>::Zero();
            auto full = make_bsdf<16>(*p), spec = make_bsdf<16>(*p), diff = make_bsdf<16>(*p);
            full->set_spectral("diffuse_reflectance", rd), full->set_spectral("specular_reflectance", rs);
            spec->set_spectral("diffuse_reflectance", zero), spec->set_spectral("specular_reflectance", rs);
            diff->set_spectral("diffuse_reflectance", rd), diff->set_spectral("specular_reflectance", zero);
            for (const auto& [wi, wo] : direction_pairs(*full, 41, 256)) {
                Spectrum<16> g = full->eval_grad_scalar(BSDFContext{}, wi, wo, 0);
                Spectrum<16> sum =
                    spec->eval_grad_scalar(BSDFContext{}, wi, wo, 0) + diff->eval_grad_scalar(BSDFContext{}, wi, wo, 0);
                EXPECT_LE((g - sum).abs().maxCoeff(), 1e-6f * (1.f + g.abs().maxCoeff())) << d;
            }
        }
}

TEST(BSDFAlpha, WeightGradIsEvalGradOverPdf) {
    // Path replay holds bs.wo and bs.pdf fixed, so ∂weight/∂α = (∂eval/∂α)/pdf for every
    // non-delta sample (docs/bsdfs.md (43)); no rough plugin overrides the default, twosided
    // forwards with the mirroring.
    std::vector<Case> cases = rough_cases(false);
    const Spectrum<16> c1 = ramp(-0.4f, 1.3f), c2 = ramp(0.9f, -0.6f);
    for (const char* d : {"beckmann", "ggx"}) {
        cases.push_back({std::string("roughplastic ") + d,
                         props("roughplastic", d),
                         {{"diffuse_reflectance", c1}, {"specular_reflectance", c2}}});
        cases.push_back({std::string("twosided roughplastic ") + d,
                         twosided(props("roughplastic", d)),
                         {{"diffuse_reflectance", c1}, {"specular_reflectance", c2}}});
    }
    for (const Case& cs : cases)
        for (float alpha : {0.1f, 0.3f, 0.7f}) {
            auto bsdf = build(cs);
            bsdf->set_scalar("alpha", alpha);
            BSDFContext ctx;
            ctx.mode = cs.mode;
            int n_valid = 0;
            for (uint32_t i = 0; i < 256; ++i) {
                float z = (i % 2 ? 1.f : -1.f) * (0.05f + 0.95f * sample_1d(51, i, 0, 0));
                float r = std::sqrt(1.f - z * z), phi = 2.f * kPi * sample_1d(51, i, 0, 1);
                Vec3f wi(r * std::cos(phi), r * std::sin(phi), z);
                BSDFSample<16> bs = bsdf->sample(ctx, wi, sample_1d(51, i, 0, 2),
                                                 Vec2f(sample_1d(51, i, 0, 3), sample_1d(51, i, 0, 4)));
                if (!bs.valid()) continue;
                ASSERT_FALSE(bs.lobe & kDelta) << cs.name;
                ++n_valid;
                Spectrum<16> g = bsdf->weight_grad_scalar(ctx, wi, bs, 0);
                Spectrum<16> expect = bsdf->eval_grad_scalar(ctx, wi, bs.wo, 0) / bs.pdf;
                EXPECT_TRUE(g.isFinite().all()) << cs.name;
                EXPECT_LE((g - expect).abs().maxCoeff(), 1e-6f * expect.abs().maxCoeff()) << cs.name << " α " << alpha;
            }
            EXPECT_GT(n_valid, 64) << cs.name << " α " << alpha;
        }
}

TEST(BSDFAlpha, SetScalarEqualsFreshConstruction) {
    // set_scalar re-derives everything cached from alpha (roughplastic: t table, Fdr_int, ρ̃,
    // and their α-derivatives): a BSDF moved to alpha b behaves bit for bit like one built with
    // b, for eval, pdf, sample, both gradients; and moving back restores the original.
    const Spectrum<16> c1 = ramp(-0.4f, 1.3f), c2 = ramp(0.9f, -0.6f);
    for (const char* type : {"roughconductor", "roughdielectric", "roughplastic", "roughplastic nonlinear", "twosided"})
        for (const char* d : {"beckmann", "ggx"}) {
            auto make = [&](float alpha) {
                std::string t = type;
                std::shared_ptr<Props> p;
                if (t == "twosided") p = twosided(props("roughconductor", d, alpha));
                else p = props(t.substr(0, t.find(' ')), d, alpha);
                if (t == "roughplastic nonlinear") p->values["nonlinear"] = true;
                auto b = make_bsdf<16>(*p);
                auto keys = b->spectral_keys();
                for (size_t k = 0; k < keys.size(); ++k) b->set_spectral(keys[k], k ? c2 : c1);
                return b;
            };
            auto moved = make(0.3f), fresh = make(0.55f), orig = make(0.3f);
            const int nkeys = int(moved->spectral_keys().size());
            auto same = [&](BSDF<16>& a, BSDF<16>& b, const char* what) {
                for (uint32_t i = 0; i < 64; ++i) {
                    float z = (i % 4 == 3 ? -1.f : 1.f) * (0.05f + 0.95f * sample_1d(61, i, 0, 0));
                    float r = std::sqrt(1.f - z * z), phi = 2.f * kPi * sample_1d(61, i, 0, 1);
                    Vec3f wi(r * std::cos(phi), r * std::sin(phi), z);
                    Vec3f wo = sphere(sample_1d(61, i, 0, 2), sample_1d(61, i, 0, 3));
                    float u1 = sample_1d(61, i, 0, 4);
                    Vec2f u2(sample_1d(61, i, 0, 5), sample_1d(61, i, 0, 6));
                    BSDFContext ctx;
                    EXPECT_TRUE((a.eval(ctx, wi, wo) == b.eval(ctx, wi, wo)).all()) << type << " " << d << " " << what;
                    EXPECT_EQ(a.pdf(ctx, wi, wo), b.pdf(ctx, wi, wo)) << type << " " << d << " " << what;
                    EXPECT_TRUE((a.eval_grad_scalar(ctx, wi, wo, 0) == b.eval_grad_scalar(ctx, wi, wo, 0)).all())
                        << type << " " << d << " " << what;
                    for (int k = 0; k < nkeys; ++k)
                        EXPECT_TRUE((a.eval_grad(ctx, wi, wo, k) == b.eval_grad(ctx, wi, wo, k)).all())
                            << type << " " << d << " " << what;
                    BSDFSample<16> sa = a.sample(ctx, wi, u1, u2), sb = b.sample(ctx, wi, u1, u2);
                    EXPECT_EQ(sa.pdf, sb.pdf) << type << " " << d << " " << what;
                    EXPECT_EQ(sa.wo, sb.wo) << type << " " << d << " " << what;
                    EXPECT_TRUE((sa.weight == sb.weight).all()) << type << " " << d << " " << what;
                    if (sa.valid()) {
                        EXPECT_TRUE(
                            (a.weight_grad_scalar(ctx, wi, sa, 0) == b.weight_grad_scalar(ctx, wi, sb, 0)).all())
                            << type << " " << d;
                    }
                }
            };
            moved->set_scalar("alpha", 0.55f);
            same(*moved, *fresh, "moved to 0.55");
            moved->set_scalar("alpha", 0.3f);
            same(*moved, *orig, "moved back to 0.3");
        }
}

TEST(BSDFAlpha, KeysRoundTripClampAndErrors) {
    for (const char* type : {"roughconductor", "roughdielectric", "roughplastic", "twosided"})
        for (const char* d : {"beckmann", "ggx"}) {
            std::string t = type;
            auto p = t == "twosided" ? twosided(props("roughplastic", d, 0.25f)) : props(t, d, 0.25f);
            auto bsdf = make_bsdf<16>(*p);
            ASSERT_EQ(bsdf->scalar_keys(), std::vector<std::string>{"alpha"}) << type;
            EXPECT_EQ(bsdf->get_scalar("alpha"), 0.25f) << type;
            for (float v : {0.37f, 0.9f, 1.7f, 1e-4f, 2e-4f}) {
                bsdf->set_scalar("alpha", v);
                EXPECT_EQ(bsdf->get_scalar("alpha"), v) << type;
            }
            for (float v : {5e-5f, 1e-6f, 0.f, -0.f, -2.f}) {  // the constructor's minimum
                bsdf->set_scalar("alpha", v);
                EXPECT_EQ(bsdf->get_scalar("alpha"), 1e-4f) << type << " " << v;
            }
            bsdf->set_scalar("alpha", 0.4f);
            EXPECT_THROW(bsdf->set_scalar("alpha", std::nanf("")), std::invalid_argument) << type;
            EXPECT_THROW(bsdf->set_scalar("alpha", INFINITY), std::invalid_argument) << type;
            EXPECT_EQ(bsdf->get_scalar("alpha"), 0.4f) << type << ": a rejected value changes nothing";
            EXPECT_THROW(bsdf->get_scalar("roughness"), std::invalid_argument) << type;
            EXPECT_THROW(bsdf->set_scalar("alpha_u", 0.3f), std::invalid_argument) << type;
            EXPECT_THROW(bsdf->eval_grad_scalar(BSDFContext{}, Vec3f(0, 0, 1), Vec3f(0, 0, 1), 1),
                         std::invalid_argument)
                << type;
            EXPECT_EQ(bsdf->get_scalar("alpha"), 0.4f) << type;
            // The constructor's clamp is the same.
            auto tiny = t == "twosided" ? twosided(props("roughplastic", d, 1e-6f)) : props(t, d, 1e-6f);
            EXPECT_EQ(make_bsdf<16>(*tiny)->get_scalar("alpha"), 1e-4f) << type;
        }
    // BSDFs without roughness expose no scalar parameter (diffuse is left to its own tests).
    for (const char* type : {"conductor", "dielectric", "plastic"}) {
        auto bsdf = make_bsdf<16>(*props(type));
        EXPECT_TRUE(bsdf->scalar_keys().empty()) << type;
        EXPECT_THROW(bsdf->get_scalar("alpha"), std::invalid_argument) << type;
        EXPECT_THROW(bsdf->set_scalar("alpha", 0.3f), std::invalid_argument) << type;
    }
    EXPECT_TRUE(make_bsdf<16>(*twosided(props("conductor")))->scalar_keys().empty());
}

TEST(BSDFAlpha, GradientsFiniteOverTheWholeRange) {
    // From the clamp (1e-4: D ~ 3e7 at the peak) to alpha > 1, at the mirror direction (the
    // peak), its neighbours, sampled directions and random ones.
    const Spectrum<16> c1 = ramp(-0.4f, 1.3f);
    for (const char* type : {"roughconductor", "roughdielectric", "roughplastic"})
        for (const char* d : {"beckmann", "ggx"})
            for (float alpha : {1e-4f, 1e-3f, 0.02f, 1.f, 2.5f}) {
                auto bsdf = make_bsdf<16>(*props(type, d, alpha));
                bsdf->set_spectral(bsdf->spectral_keys()[0], c1);
                for (uint32_t i = 0; i < 128; ++i) {
                    float z = (i % 2 ? 1.f : -1.f) * (0.01f + 0.99f * sample_1d(71, i, 0, 0));
                    float r = std::sqrt(1.f - z * z), phi = 2.f * kPi * sample_1d(71, i, 0, 1);
                    Vec3f wi(r * std::cos(phi), r * std::sin(phi), z);
                    Vec3f mirror(-wi.x(), -wi.y(), wi.z());
                    for (const Vec3f& wo : {mirror, Vec3f((mirror + Vec3f(1e-3f, 0.f, 0.f)).normalized()), Vec3f(-wi),
                                            sphere(sample_1d(71, i, 0, 2), sample_1d(71, i, 0, 3))})
                        EXPECT_TRUE(bsdf->eval_grad_scalar(BSDFContext{}, wi, wo, 0).isFinite().all())
                            << type << " " << d << " " << alpha;
                    BSDFSample<16> bs = bsdf->sample(BSDFContext{}, wi, sample_1d(71, i, 0, 4),
                                                     Vec2f(sample_1d(71, i, 0, 5), sample_1d(71, i, 0, 6)));
                    if (bs.valid()) {
                        EXPECT_TRUE(bsdf->weight_grad_scalar(BSDFContext{}, wi, bs, 0).isFinite().all())
                            << type << " " << d << " " << alpha;
                    }
                }
            }
}
