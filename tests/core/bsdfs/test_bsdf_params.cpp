// Spectral coefficients exposed for fitting: every BSDF is affine in each of its coefficients
// (f(a + b) - f(a) - f(b) + f(0) = 0 channel-wise; nonlinear plastics excepted), signed values
// included, for eval and for sample weights, and unknown keys are rejected. The analytic
// coefficient gradients (eval_grad, weight_grad; docs/bsdfs.md (30)-(36)) match central
// differences for every plugin, and every registered type provides them.
#include "core/bsdf.h"
#include "core/error.h"
#include "core/sampler.h"
#include <gtest/gtest.h>
#include <cmath>
#include <sstream>

using namespace lpt;

namespace {

std::shared_ptr<Props> props(const std::string& type) {
    auto p = std::make_shared<Props>();
    p->type = type;
    p->file = "test";
    if (type.rfind("rough", 0) == 0) p->values["alpha"] = 0.3f;
    return p;
}

std::shared_ptr<Props> twosided(std::shared_ptr<Props> nested) {
    auto p = props("twosided");
    p->values["bsdf"] = std::move(nested);
    return p;
}

std::shared_ptr<Props> with(std::shared_ptr<Props> p, const std::string& key, PropValue v) {
    p->values[key] = std::move(v);
    return p;
}

Spectrum<16> ramp(float a, float b) {
    Spectrum<16> s;
    for (int c = 0; c < 16; ++c) s[c] = a + b * float(c) / 15.f;
    return s;
}

}  // namespace

TEST(BSDFParams, EveryCoefficientEntersAffinely) {
    for (const char* type : {"diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric", "plastic",
                             "roughplastic", "twosided"}) {
        std::shared_ptr<Props> p = props(type);
        if (std::string(type) == "twosided") p->values["bsdf"] = props("roughplastic");
        auto bsdf = make_bsdf<16>(*p);
        auto keys = bsdf->spectral_keys();
        ASSERT_FALSE(keys.empty()) << type;
        const Spectrum<16> a = ramp(-0.4f, 0.9f), b = ramp(0.3f, -0.7f), zero = Spectrum<16>::Zero();
        for (const std::string& key : keys) {
            for (uint32_t i = 0; i < 64; ++i) {
                Vec3f wi =
                    Vec3f(sample_1d(1, i, 0, 0) - 0.5f, sample_1d(1, i, 0, 1) - 0.5f, 0.2f + sample_1d(1, i, 0, 2))
                        .normalized();
                float u1 = sample_1d(1, i, 0, 3);
                Vec2f u2(sample_1d(1, i, 0, 4), sample_1d(1, i, 0, 5));
                auto run = [&](const Spectrum<16>& v, Vec3f* wo_out) {
                    bsdf->set_spectral(key, v);
                    BSDFSample<16> bs = bsdf->sample(BSDFContext{}, wi, u1, u2);
                    if (wo_out) *wo_out = bs.wo;
                    return std::pair{bs,
                                     bs.valid() ? bsdf->eval(BSDFContext{}, wi, bs.wo) : Spectrum<16>::Zero().eval()};
                };
                Vec3f wo;
                auto [s_ab, e_ab] = run(a + b, &wo);
                auto [s_a, e_a] = run(a, nullptr);
                auto [s_b, e_b] = run(b, nullptr);
                auto [s_0, e_0] = run(zero, nullptr);
                // Sampling never looks at the coefficients.
                ASSERT_EQ(s_ab.valid(), s_0.valid()) << type << " " << key;
                if (!s_ab.valid()) continue;
                EXPECT_EQ(s_ab.wo, s_0.wo) << type << " " << key;
                Spectrum<16> dw = s_ab.weight - s_a.weight - s_b.weight + s_0.weight;
                Spectrum<16> de = e_ab - e_a - e_b + e_0;
                float scale = 1.f + s_ab.weight.abs().maxCoeff() + e_ab.abs().maxCoeff();
                EXPECT_LT(dw.abs().maxCoeff(), 1e-5f * scale) << type << " " << key;
                EXPECT_LT(de.abs().maxCoeff(), 1e-5f * scale) << type << " " << key;
            }
        }
        EXPECT_THROW(bsdf->set_spectral("no_such_key", Spectrum<16>::Zero()), std::invalid_argument) << type;
    }
}

/// eval_grad (at random wo and at sampled wo) and weight_grad of coefficient `key` against central
/// differences between coefficient values cp and cm (`step` = cp - cm), at 64 directions.
static void expect_gradients_match(BSDF<16>& b, const std::string& name, int key, const std::string& key_name,
                                   const Spectrum<16>& c, const Spectrum<16>& step, const Spectrum<16>& cp,
                                   const Spectrum<16>& cm, float tol) {
    BSDF<16>* bsdf = &b;
    int n_valid = 0;
    for (uint32_t i = 0; i < 64; ++i) {
        float z = (i % 2 ? 1.f : -1.f) * (0.2f + sample_1d(2, i, 0, 2));  // both faces
        Vec3f wi = Vec3f(sample_1d(2, i, 0, 0) - 0.5f, sample_1d(2, i, 0, 1) - 0.5f, z).normalized();
        float u1 = sample_1d(2, i, 0, 3);
        Vec2f u2(sample_1d(2, i, 0, 4), sample_1d(2, i, 0, 5));
        // eval_grad also off the sampler: wo uniform on the whole sphere.
        float zr = 2.f * sample_1d(2, i, 0, 6) - 1.f, phi = 2.f * kPi * sample_1d(2, i, 0, 7);
        float rr = std::sqrt(std::max(0.f, 1.f - zr * zr));
        Vec3f wr(rr * std::cos(phi), rr * std::sin(phi), zr);
        bsdf->set_spectral(key_name, c);
        BSDFSample<16> bs = bsdf->sample(BSDFContext{}, wi, u1, u2);
        Spectrum<16> g_rand = bsdf->eval_grad(BSDFContext{}, wi, wr, key);
        bsdf->set_spectral(key_name, cp);
        Spectrum<16> rp = bsdf->eval(BSDFContext{}, wi, wr);
        bsdf->set_spectral(key_name, cm);
        Spectrum<16> rm = bsdf->eval(BSDFContext{}, wi, wr);
        Spectrum<16> fd_rand = (rp - rm) / step;
        EXPECT_LT((g_rand - fd_rand).abs().maxCoeff(), tol * (1.f + fd_rand.abs().maxCoeff()))
            << name << " " << key_name << " random wo";
        if (!bs.valid()) continue;
        ++n_valid;
        bsdf->set_spectral(key_name, c);
        Spectrum<16> g_eval = bsdf->eval_grad(BSDFContext{}, wi, bs.wo, key);
        Spectrum<16> g_weight = bsdf->weight_grad(BSDFContext{}, wi, bs, key);
        bsdf->set_spectral(key_name, cp);
        BSDFSample<16> bp = bsdf->sample(BSDFContext{}, wi, u1, u2);
        Spectrum<16> ep = bsdf->eval(BSDFContext{}, wi, bs.wo);
        bsdf->set_spectral(key_name, cm);
        BSDFSample<16> bm = bsdf->sample(BSDFContext{}, wi, u1, u2);
        Spectrum<16> em = bsdf->eval(BSDFContext{}, wi, bs.wo);
        ASSERT_TRUE(bp.valid() && bm.valid() && bp.lobe == bs.lobe && bm.lobe == bs.lobe) << name;
        Spectrum<16> fd_eval = (ep - em) / step, fd_weight = (bp.weight - bm.weight) / step;
        EXPECT_LT((g_eval - fd_eval).abs().maxCoeff(), tol * (1.f + fd_eval.abs().maxCoeff()))
            << name << " " << key_name;
        EXPECT_LT((g_weight - fd_weight).abs().maxCoeff(), tol * (1.f + fd_weight.abs().maxCoeff()))
            << name << " " << key_name << " lobe " << bs.lobe;
    }
    EXPECT_GT(n_valid, 16) << name;  // the sampled branch was actually exercised
}

TEST(BSDFParams, CoefficientGradientsMatchFiniteDifferences) {
    const PropValue eta = Eigen::Array3f(0.2f, 0.9f, 1.1f), k = Eigen::Array3f(3.9f, 2.4f, 2.2f);
    const PropValue ggx = std::string("ggx");
    struct Case {
        std::string name;
        std::shared_ptr<Props> p;
        int curved_key = -1;  ///< the one coefficient that enters non-affinely, if any
    };
    // Affine coefficients: the central difference is exact up to rounding for any step, so a
    // large h keeps rounding small (~eps |f| / h ~ 1e-7, measured <= 2e-7) and 1e-4 is tight.
    // nonlinear = true plastics: b(d) = d/(1 - d Fdr) is curved in d = diffuse_reflectance
    // (key 0), so that key needs a small step. Truncation error of the central difference:
    // h^2 b'''/6 with b''' = 6 Fdr^2/(1 - d Fdr)^4 <= 9 for Fdr_int ~ 0.6 and d in [-0.4, 0.5]
    // (1 - d Fdr >= 0.7), i.e. <= 1.5e-6 at h = 1e-3. Rounding: eval/weight carry a few float
    // ulps (say 5 eps |f|, eps = 6e-8) divided by the step 2h: <= 1.5e-4 |f| (measured
    // <= 2e-5). A 1e-3 relative tolerance keeps a >= 5x margin over that bound and still
    // catches any wrong factor (the affine 1/(1 - Fdr) or 1/(1 - d Fdr) in place of
    // 1/(1 - d Fdr)^2 is off by >= 20% over this ramp).
    const float h_affine = 0.25f, tol_affine = 1e-4f, h_curved = 1e-3f, tol_curved = 1e-3f;
    const std::vector<Case> cases = {
        {"diffuse", props("diffuse")},
        {"conductor", props("conductor")},
        {"conductor eta/k", with(with(props("conductor"), "eta", eta), "k", k)},
        {"dielectric", props("dielectric")},
        {"twosided diffuse", twosided(props("diffuse"))},
        {"roughconductor", props("roughconductor")},
        {"roughconductor eta/k", with(with(props("roughconductor"), "eta", eta), "k", k)},
        {"roughconductor ggx eta/k",
         with(with(with(props("roughconductor"), "eta", eta), "k", k), "distribution", ggx)},
        {"roughdielectric", props("roughdielectric")},
        {"roughdielectric ggx", with(props("roughdielectric"), "distribution", ggx)},
        {"plastic", props("plastic")},
        {"roughplastic", props("roughplastic")},
        {"roughplastic ggx", with(props("roughplastic"), "distribution", ggx)},
        {"twosided roughplastic", twosided(props("roughplastic"))},
        {"plastic nonlinear", with(props("plastic"), "nonlinear", true), 0},
        {"roughplastic nonlinear", with(props("roughplastic"), "nonlinear", true), 0},
        {"twosided roughplastic nonlinear", twosided(with(props("roughplastic"), "nonlinear", true)), 0},
    };
    for (const Case& cs : cases) {
        auto bsdf = make_bsdf<16>(*cs.p);
        auto keys = bsdf->spectral_keys();
        ASSERT_FALSE(keys.empty()) << cs.name;
        for (int key = 0; key < int(keys.size()); ++key) {
            // The other coefficients stay at their (nonzero) defaults, so a cross-term that
            // leaked into the derivative would show.
            const Spectrum<16> c = ramp(-0.4f, 0.9f);
            const float h = key == cs.curved_key ? h_curved : h_affine;
            const float tol = key == cs.curved_key ? tol_curved : tol_affine;
            const Spectrum<16> cp = c + h, cm = c - h;
            const Spectrum<16> step = cp - cm;  // the exact float step, per channel
            expect_gradients_match(*bsdf, cs.name, key, keys[key], c, step, cp, cm, tol);
        }
    }
}

TEST(BSDFParams, EveryRegisteredTypeHasFiniteGradients) {
    // No plugin is left without gradients (the base-class eval_grad throws std::logic_error).
    // The registered types are read from make_bsdf's "unknown type" error, so a newly
    // registered plugin is covered without touching this test.
    std::vector<std::string> types;
    try {
        make_bsdf<16>(*props("no_such_bsdf_type"));
        FAIL() << "unknown type accepted";
    } catch (const SceneError& e) {
        std::string msg = e.what();
        size_t at = msg.find("(known: ");
        ASSERT_NE(at, std::string::npos) << msg;
        at += 8;
        std::stringstream list(msg.substr(at, msg.find(')', at) - at));
        for (std::string t; std::getline(list, t, ',');) types.push_back(t.substr(t.find_first_not_of(' ')));
    }
    ASSERT_GE(types.size(), 8u);
    for (const std::string& type : types) {
        for (bool nonlinear : {false, true}) {
            std::shared_ptr<Props> inner = props(type == "twosided" ? "roughplastic" : type);
            if (nonlinear) {
                if (inner->type.find("plastic") == std::string::npos) continue;
                inner->values["nonlinear"] = true;
            }
            auto bsdf = make_bsdf<16>(*(type == "twosided" ? twosided(inner) : inner));
            auto keys = bsdf->spectral_keys();
            EXPECT_FALSE(keys.empty()) << type;
            for (int key = 0; key < int(keys.size()); ++key) {
                bsdf->set_spectral(keys[key], ramp(-0.4f, 0.9f));
                for (uint32_t i = 0; i < 64; ++i) {
                    float z = (i % 2 ? 1.f : -1.f) * (0.05f + sample_1d(3, i, 0, 2));
                    Vec3f wi = Vec3f(sample_1d(3, i, 0, 0) - 0.5f, sample_1d(3, i, 0, 1) - 0.5f, z).normalized();
                    Vec2f u2(sample_1d(3, i, 0, 4), sample_1d(3, i, 0, 5));
                    BSDFSample<16> bs = bsdf->sample(BSDFContext{}, wi, sample_1d(3, i, 0, 3), u2);
                    Spectrum<16> g = Spectrum<16>::Zero();
                    for (const Vec3f& wo : {Vec3f(-wi), Vec3f(-wi.x(), -wi.y(), wi.z())}) {
                        ASSERT_NO_THROW(g = bsdf->eval_grad(BSDFContext{}, wi, wo, key)) << type;
                        EXPECT_TRUE(g.isFinite().all()) << type << " " << keys[key];
                    }
                    if (!bs.valid()) continue;
                    ASSERT_NO_THROW(g = bsdf->eval_grad(BSDFContext{}, wi, bs.wo, key)) << type;
                    EXPECT_TRUE(g.isFinite().all()) << type << " " << keys[key];
                    ASSERT_NO_THROW(g = bsdf->weight_grad(BSDFContext{}, wi, bs, key)) << type;
                    EXPECT_TRUE(g.isFinite().all()) << type << " " << keys[key];
                }
            }
        }
    }
}
