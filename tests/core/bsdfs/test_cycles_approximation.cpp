// The validation-only key cycles_approximation (docs/bsdfs.md (47)-(49)): what it replaces must
// keep each lobe's energy for every view direction (the translation's claim that its
// approximations are exact under uniform illumination), the sampled BSDFs must stay consistent,
// and latent BSDFs must refuse it.
#include "chi2.h"
#include "core/bsdf.h"
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/rough_transmittance.h"

namespace lpt {
namespace {

using namespace lpt::test;

Props with_approximation(Props p) {
    p.values["cycles_approximation"] = true;
    return p;
}

/// Mean and standard error of a's sample weight minus b's, both sampled with the same numbers
/// (the two BSDFs sample alike, so the noise they share cancels).
Albedo paired_difference(const BSDF<3>& a, const BSDF<3>& b, const Vec3f& wi, int n = 100000) {
    const BSDFContext ctx;
    return sample_mean(5, n, [&](float u1, const Vec2f& u2) {
        return sample_weight_mean(a, ctx, wi, u1, u2) - sample_weight_mean(b, ctx, wi, u1, u2);
    });
}

const std::vector<Props> kCoatings = {
    props("plastic", {{"int_ior", 1.5f}, {"diffuse_reflectance", rgb(0.8f, 0.4f, 0.1f)}}),
    props("plastic", {{"int_ior", 1.5f}, {"nonlinear", true}, {"diffuse_reflectance", rgb(1.f, 1.f, 1.f)}}),
    props("roughplastic",
          {{"alpha", 0.1f}, {"int_ior", 1.5f}, {"nonlinear", true}, {"diffuse_reflectance", rgb(1.f, 1.f, 1.f)}}),
    props("roughplastic", {{"distribution", std::string("ggx")},
                           {"alpha", 0.2f},
                           {"int_ior", 1.5f},
                           {"diffuse_reflectance", rgb(0.05f, 0.3f, 0.6f)}}),
    props("roughplastic", {{"alpha", 0.5f}, {"int_ior", 1.33f}, {"diffuse_reflectance", rgb(0.5f, 0.5f, 0.5f)}}),
};

TEST(CyclesApproximation, CoatingsKeepTheirAlbedoAtEveryViewAngle) {
    // Replacing t(cos θo) by its cosine-weighted mean, and R(wi·h) by R(μi)/A_g(μi), moves energy
    // between outgoing directions but keeps the total for each wi: both albedos must agree.
    for (const Props& p : kCoatings) {
        auto exact = make_bsdf<3>(p);
        auto approx = make_bsdf<3>(with_approximation(p));
        for (float cos_i : {0.95f, 0.6f, 0.3f, 0.1f}) {
            const Vec3f wi = dir(cos_i, 0.4f);
            const Albedo a = albedo(*exact, wi, TransportMode::Radiance, 400000);
            const Albedo b = albedo(*approx, wi, TransportMode::Radiance, 400000);
            const double sigma = std::hypot(a.se, b.se);
            EXPECT_NEAR(b.mean, a.mean, 4.0 * sigma + 1e-3) << describe(p) << ", cos wi = " << cos_i;
        }
    }
}

TEST(CyclesApproximation, CoatingsMoveEnergyTowardGrazingLight) {
    // The light-side factor becomes a constant: where the exact t(cos θo) falls toward grazing
    // light, the approximation is brighter, and dimmer toward normal light. Without this the key
    // would not be read at all.
    for (const Props& p : kCoatings) {
        // Dark bases are left out: there the specular lobe's tail outweighs the diffuse lobe.
        if (std::get<Eigen::Array3f>(p.values.at("diffuse_reflectance")).mean() < 0.3f) continue;
        auto exact = make_bsdf<3>(p);
        auto approx = make_bsdf<3>(with_approximation(p));
        BSDFContext ctx;
        const Vec3f wi = dir(0.7f, 0.f);
        const Vec3f grazing = dir(0.05f, 2.f), normal = dir(0.99f, 2.f);  // far from the specular peak
        const float g = approx->eval(ctx, wi, grazing).mean() / exact->eval(ctx, wi, grazing).mean();
        const float n = approx->eval(ctx, wi, normal).mean() / exact->eval(ctx, wi, normal).mean();
        EXPECT_GT(g, 1.05f) << describe(p);
        EXPECT_LT(n, 1.f) << describe(p);
    }
}

TEST(CyclesApproximation, SamplingStaysConsistent) {
    std::vector<Props> all = kCoatings;
    all.push_back(
        props("roughconductor", {{"alpha", 0.3f}, {"eta", rgb(0.2f, 0.9f, 1.1f)}, {"k", rgb(3.9f, 2.4f, 2.2f)}}));
    const std::vector<Vec3f> wis = {dir(0.9f, 0.3f), dir(0.4f, 1.f), dir(0.15f, 2.f)};
    for (const Props& p : all) {
        const Props q = with_approximation(p);
        expect_weights(q, wis, TransportMode::Radiance);
        expect_chi2(q, wis, 1e-4);
    }
}

TEST(CyclesApproximation, MacroNormalFresnelFactorsOutOfTheConductorLobe) {
    // F(cos θi) at the macro normal is a constant of the integral over wo, so the albedo is
    // exactly F(cos θi) times the Fresnel-free lobe's (the perfect conductor, F = 1), sample by
    // sample; the exact model's F(wi·m) gives a different albedo at grazing view.
    const Eigen::Array3f eta(1.65746f, 0.880369f, 0.521229f), k(9.22387f, 6.26952f, 4.837f);  // classroom's chairs
    for (const char* distr : {"beckmann", "ggx"}) {
        const Values rough = {{"distribution", std::string(distr)}, {"alpha", 0.4f}};
        Values metal = rough;
        metal.push_back({"eta", eta});
        metal.push_back({"k", k});
        auto mirror = make_bsdf<3>(props("roughconductor", rough));
        auto approx = make_bsdf<3>(with_approximation(props("roughconductor", metal)));
        auto exact = make_bsdf<3>(props("roughconductor", metal));
        for (float cos_i : {0.9f, 0.4f, 0.1f}) {
            const Vec3f wi = dir(cos_i, 1.f);
            const double f = fresnel_conductor<3>(cos_i, Spectrum<3>(eta), Spectrum<3>(k)).mean();
            const Albedo lobe = albedo(*mirror, wi, TransportMode::Radiance);
            const Albedo a = albedo(*approx, wi, TransportMode::Radiance);
            EXPECT_NEAR(a.mean, f * lobe.mean, 1e-5) << distr << ", cos wi = " << cos_i;
            if (cos_i < 0.2f) {
                const Albedo d = paired_difference(*exact, *approx, wi);
                EXPECT_GT(std::abs(d.mean), 5.0 * d.se) << distr << ": exact − approximated " << d.mean;
            }
        }
    }
}

TEST(CyclesApproximation, GlossyTableIsTheFresnelFreeLobesAlbedo) {
    // A_g of (49) by the table's quadrature against the sampled albedo of a perfect conductor.
    for (MicrofacetType type : {MicrofacetType::Beckmann, MicrofacetType::GGX})
        for (float alpha : {0.1f, 0.5f}) {
            const TransmittanceTable a = rough_lobe_table_direct(type, 1.5f, alpha, CoatingLobe::Glossy);
            auto mirror = make_bsdf<3>(props(
                "roughconductor",
                {{"distribution", std::string(type == MicrofacetType::GGX ? "ggx" : "beckmann")}, {"alpha", alpha}}));
            for (int j : {8, 32, 63}) {
                const float mu = float(j) / (kTransmittanceRes - 1);
                const Albedo s = albedo(*mirror, dir(mu, 0.3f), TransportMode::Radiance, 400000);
                EXPECT_NEAR(a.t[j], s.mean, 4.0 * s.se + 2e-4)
                    << (type == MicrofacetType::GGX ? "ggx" : "beckmann") << " alpha " << alpha << ", mu " << mu;
            }
        }
}

TEST(CyclesApproximation, LatentBsdfsRefuseTheKey) {
    for (const Props& p : {kCoatings[0], kCoatings[2], props("roughconductor", {{"alpha", 0.2f}})}) {
        try {
            make_bsdf<16>(with_approximation(p));
            ADD_FAILURE() << describe(p) << ": accepted in a latent BSDF";
        } catch (const SceneError& e) {
            EXPECT_NE(std::string(e.what()).find("cycles_approximation"), std::string::npos) << e.what();
        }
        EXPECT_NO_THROW(make_bsdf<16>(p)) << describe(p);
    }
}

}  // namespace
}  // namespace lpt
