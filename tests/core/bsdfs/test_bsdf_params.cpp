// Spectral coefficients exposed for fitting: every BSDF is affine in each of its coefficients
// (f(a + b) - f(a) - f(b) + f(0) = 0 channel-wise), signed values included, for eval and for
// sample weights, and unknown keys are rejected.
#include "core/bsdf.h"
#include "core/sampler.h"
#include <gtest/gtest.h>

using namespace lpt;

namespace {

std::shared_ptr<Props> props(const std::string& type) {
    auto p = std::make_shared<Props>();
    p->type = type;
    p->file = "test";
    if (type.rfind("rough", 0) == 0) p->values["alpha"] = 0.3f;
    return p;
}

Spectrum<16> ramp(float a, float b) {
    Spectrum<16> s;
    for (int c = 0; c < 16; ++c) s[c] = a + b * float(c) / 15.f;
    return s;
}

}  // namespace

TEST(BSDFParams, EveryCoefficientEntersAffinely) {
    for (const char* type : {"diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric", "plastic", "roughplastic", "twosided"}) {
        std::shared_ptr<Props> p = props(type);
        if (std::string(type) == "twosided") p->values["bsdf"] = props("roughplastic");
        auto bsdf = make_bsdf<16>(*p);
        auto keys = bsdf->spectral_keys();
        ASSERT_FALSE(keys.empty()) << type;
        const Spectrum<16> a = ramp(-0.4f, 0.9f), b = ramp(0.3f, -0.7f), zero = Spectrum<16>::Zero();
        for (const std::string& key : keys) {
            for (uint32_t i = 0; i < 64; ++i) {
                Vec3f wi = Vec3f(sample_1d(1, i, 0, 0) - 0.5f, sample_1d(1, i, 0, 1) - 0.5f, 0.2f + sample_1d(1, i, 0, 2)).normalized();
                float u1 = sample_1d(1, i, 0, 3);
                Vec2f u2(sample_1d(1, i, 0, 4), sample_1d(1, i, 0, 5));
                auto run = [&](const Spectrum<16>& v, Vec3f* wo_out) {
                    bsdf->set_spectral(key, v);
                    BSDFSample<16> bs = bsdf->sample(BSDFContext{}, wi, u1, u2);
                    if (wo_out) *wo_out = bs.wo;
                    return std::pair{bs, bs.valid() ? bsdf->eval(BSDFContext{}, wi, bs.wo) : Spectrum<16>::Zero().eval()};
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

TEST(BSDFParams, CoefficientGradientsMatchFiniteDifferences) {
    // Differentiable plugins so far; the others must say so instead of returning garbage.
    for (const char* type : {"diffuse", "conductor", "dielectric", "twosided"}) {
        std::shared_ptr<Props> p = props(type);
        if (std::string(type) == "twosided") p->values["bsdf"] = props("diffuse");
        auto bsdf = make_bsdf<16>(*p);
        auto keys = bsdf->spectral_keys();
        for (int key = 0; key < int(keys.size()); ++key) {
            const Spectrum<16> c = ramp(-0.4f, 0.9f);
            const float h = 0.25f;  // affine: any step is exact up to rounding
            for (uint32_t i = 0; i < 64; ++i) {
                float z = (i % 2 ? 1.f : -1.f) * (0.2f + sample_1d(2, i, 0, 2));  // both faces
                Vec3f wi = Vec3f(sample_1d(2, i, 0, 0) - 0.5f, sample_1d(2, i, 0, 1) - 0.5f, z).normalized();
                float u1 = sample_1d(2, i, 0, 3);
                Vec2f u2(sample_1d(2, i, 0, 4), sample_1d(2, i, 0, 5));
                bsdf->set_spectral(keys[key], c);
                BSDFSample<16> bs = bsdf->sample(BSDFContext{}, wi, u1, u2);
                if (!bs.valid()) continue;
                Spectrum<16> g_eval = bsdf->eval_grad(BSDFContext{}, wi, bs.wo, key);
                Spectrum<16> g_weight = bsdf->weight_grad(BSDFContext{}, wi, bs, key);
                bsdf->set_spectral(keys[key], c + h);
                BSDFSample<16> bp = bsdf->sample(BSDFContext{}, wi, u1, u2);
                Spectrum<16> ep = bsdf->eval(BSDFContext{}, wi, bs.wo);
                bsdf->set_spectral(keys[key], c - h);
                BSDFSample<16> bm = bsdf->sample(BSDFContext{}, wi, u1, u2);
                Spectrum<16> em = bsdf->eval(BSDFContext{}, wi, bs.wo);
                Spectrum<16> fd_eval = (ep - em) / (2 * h), fd_weight = (bp.weight - bm.weight) / (2 * h);
                EXPECT_LT((g_eval - fd_eval).abs().maxCoeff(), 1e-4f * (1.f + fd_eval.abs().maxCoeff())) << type << " " << keys[key];
                EXPECT_LT((g_weight - fd_weight).abs().maxCoeff(), 1e-4f * (1.f + fd_weight.abs().maxCoeff())) << type << " " << keys[key];
            }
        }
    }
    auto rough = make_bsdf<16>(*props("roughconductor"));
    EXPECT_THROW(rough->eval_grad(BSDFContext{}, Vec3f::UnitZ(), Vec3f::UnitZ(), 0), std::logic_error);
}
