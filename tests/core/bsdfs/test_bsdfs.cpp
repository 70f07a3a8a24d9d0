// Tests for every BSDF plugin (core/bsdfs/*, docs/bsdfs.md): chi-square of sample() against
// pdf(), weight == eval/pdf, reciprocity, energy bounds, registry errors, signed coefficients.
// Fixed seeds throughout: results are deterministic, thresholds are real.
#include "chi2.h"
#include "core/bsdf.h"
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/microfacet.h"
#include "core/bsdfs/rough_transmittance.h"
#include <array>

namespace lpt {
namespace {

using namespace lpt::test;

// Upper bound on the chi-square tests this file runs (108 today); Sidak keeps the family-wise
// level at 1%.
constexpr int kChi2Tests = 120;
const double kSignificance = test::sidak_significance(0.01, kChi2Tests);

const std::vector<Vec3f> kUpper = {dir(0.95f, 0.3f), dir(0.6f, 2.f), dir(0.2f, 4.f)};
const std::vector<Vec3f> kBothSides = {dir(0.95f, 0.3f), dir(0.5f, 2.f),  dir(0.15f, 4.f),
                                       dir(-0.9f, 1.f),  dir(-0.6f, 3.f), dir(-0.2f, 5.5f)};

/// Each rough type with both distributions and roughness 0.05 / 0.3 / 0.7, plus `extra`.
std::vector<Props> rough_sets(const std::string& type, const Values& extra = {}) {
    std::vector<Props> out;
    for (const char* d : {"beckmann", "ggx"})
        for (float a : {0.05f, 0.3f, 0.7f}) {
            Values v = extra;
            v.push_back({"distribution", std::string(d)});
            v.push_back({"alpha", a});
            out.push_back(props(type, v));
        }
    return out;
}

void expect_chi2(const Props& p, const std::vector<Vec3f>& wis) { test::expect_chi2(p, wis, kSignificance); }

// ---------------------------------------------------------------------------------------------
TEST(Fresnel, DielectricNormalIncidenceSnellAndStokes) {
    FresnelDielectric f = fresnel_dielectric(1.f, 1.5f);
    EXPECT_NEAR(f.R, 0.04f, 1e-6f);
    EXPECT_FLOAT_EQ(f.cos_t, -1.f);
    FresnelDielectric g = fresnel_dielectric(0.5f, 1.5f);
    float sin_t = std::sqrt(1.f - g.cos_t * g.cos_t);
    EXPECT_NEAR(sin_t, std::sqrt(0.75f) / 1.5f, 1e-6f);
    FresnelDielectric back = fresnel_dielectric(g.cos_t, 1.5f);  // same ray, reversed
    EXPECT_NEAR(back.R, g.R, 1e-6f);
    EXPECT_NEAR(back.cos_t, 0.5f, 1e-6f);
    FresnelDielectric tir = fresnel_dielectric(-0.3f, 1.5f);  // inside, beyond the critical angle
    EXPECT_EQ(tir.R, 1.f);
    EXPECT_EQ(tir.cos_t, 0.f);
}

TEST(Fresnel, ConductorLimits) {
    for (float c : {1.f, 0.7f, 0.3f, 0.05f}) {
        EXPECT_NEAR(fresnel_conductor<3>(c, Spectrum<3>::Constant(1.5f), Spectrum<3>::Zero())[0],
                    fresnel_dielectric(c, 1.5f).R, 1e-5f);
        EXPECT_NEAR(fresnel_conductor<3>(c, Spectrum<3>::Zero(), Spectrum<3>::Ones())[0], 1.f, 1e-6f);
    }
    Spectrum<3> gold = fresnel_conductor<3>(1.f, Spectrum<3>(0.2f, 0.9f, 1.1f), Spectrum<3>(3.9f, 2.4f, 2.2f));
    Spectrum<3> expect;  // normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2)
    for (int i = 0; i < 3; ++i) {
        float n = std::array<float, 3>{0.2f, 0.9f, 1.1f}[i], k = std::array<float, 3>{3.9f, 2.4f, 2.2f}[i];
        expect[i] = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
    }
    EXPECT_LT((gold - expect).abs().maxCoeff(), 1e-5f);
}

TEST(Fresnel, DiffuseReflectanceKnownValueAndIdentity) {
    EXPECT_NEAR(fresnel_diffuse_reflectance(1.5f), 0.0918f, 5e-4f);  // d'Eon & Irving's fit: 0.09179
    for (float eta : {1.33f, 1.5f, 2.f})                             // 1 - Fdr(1/eta) = (1 - Fdr(eta)) / eta^2
        EXPECT_NEAR(1.f - fresnel_diffuse_reflectance(1.f / eta),
                    (1.f - fresnel_diffuse_reflectance(eta)) / (eta * eta), 1e-5f);
}

TEST(Microfacet, DistributionAndVisibleNormalsNormalised) {
    for (MicrofacetType t : {MicrofacetType::Beckmann, MicrofacetType::GGX})
        for (float alpha : {0.05f, 0.3f, 0.7f}) {
            MicrofacetDistribution d(t, alpha);
            for (float cos_i : {1.f, 0.6f, 0.2f}) {
                Vec3f wi = dir(cos_i, 0.7f);
                double proj = 0.0, vis = 0.0;   // ∫ D cos dm = 1, ∫ G1 <wi,m> D dm = cos wi
                const int nt = 2000, np = 128;  // theta grid refined where the lobe is
                for (int a = 0; a < nt; ++a) {
                    double u = (a + 0.5) / nt, theta = 0.5 * kPi * u * u, dtheta = kPi * u / nt;
                    for (int b = 0; b < np; ++b) {
                        Vec3f m = test::sphere_dir(theta, 2.0 * kPi * (b + 0.5) / np);
                        double dw = std::sin(theta) * dtheta * 2.0 * kPi / np;
                        proj += d.D(m) * m.z() * dw;
                        vis += d.G1(wi, m) * std::max(0.f, wi.dot(m)) * d.D(m) * dw;
                    }
                }
                EXPECT_NEAR(proj, 1.0, 2e-3) << "alpha " << alpha;
                EXPECT_NEAR(vis, cos_i, 2e-3) << "alpha " << alpha << " cos wi " << cos_i;
            }
        }
}

TEST(Microfacet, SampleMatchesPdfChi2) {
    for (MicrofacetType t : {MicrofacetType::Beckmann, MicrofacetType::GGX})
        for (float alpha : {0.05f, 0.3f, 0.7f}) {
            MicrofacetDistribution d(t, alpha);
            for (const Vec3f& wi : kUpper) {
                Rng rng(5);
                auto sample = [&]() -> std::optional<Vec3f> { return d.sample(wi, rng.next2()); };
                auto pdf = [&](const Vec3f& m) { return d.pdf(wi, m); };
                test::Chi2Result r = test::chi2_sphere_test(sample, pdf, 100000, kSignificance);
                EXPECT_TRUE(r.passed) << "alpha " << alpha << ", cos wi " << wi.z() << ": " << r.summary;
            }
        }
}

TEST(Diffuse, SampleMatchesPdfChi2) { expect_chi2(props("diffuse"), kUpper); }
TEST(Diffuse, WeightMatchesEvalOverPdf) { expect_weights(props("diffuse"), kUpper, TransportMode::Radiance); }
TEST(Diffuse, Reciprocity) { expect_reciprocal(props("diffuse", {{"reflectance", rgb(0.2f, 0.5f, 0.9f)}}), false); }
TEST(Diffuse, AlbedoEqualsReflectanceAndIsOneSided) {
    auto bsdf = make_bsdf<3>(props("diffuse", {{"reflectance", rgb(0.3f, 0.6f, 0.9f)}}));
    for (const Vec3f& wi : kUpper) {
        EXPECT_NEAR(albedo(*bsdf, wi, TransportMode::Radiance).mean, 0.6, 1e-6);
        EXPECT_EQ(bsdf->eval({}, Vec3f(-wi), dir(0.5f, 1.f)).abs().maxCoeff(), 0.f);
        EXPECT_FALSE(bsdf->sample({}, Vec3f(-wi), 0.5f, Vec2f(0.3f, 0.3f)).valid());
    }
}

TEST(Diffuse, SignedReflectanceIsLinearAndUnclamped) {
    auto neg = make_bsdf<3>(props("diffuse", {{"reflectance", rgb(-0.5f, 0.2f, 0.f)}}));
    auto pos = make_bsdf<3>(props("diffuse", {{"reflectance", rgb(0.5f, 0.2f, 0.f)}}));
    Vec3f wi = dir(0.7f, 0.2f), wo = dir(0.4f, 2.5f);
    Spectrum<3> fn = neg->eval({}, wi, wo), fp = pos->eval({}, wi, wo);
    EXPECT_EQ(fn[0], -fp[0]);
    EXPECT_EQ(fn[1], fp[1]);
    EXPECT_EQ(fn[2], 0.f);
    EXPECT_NEAR(fn[0], -0.5f * 0.4f * kInvPi, 1e-7f);
    BSDFSample<3> bs = neg->sample({}, wi, 0.5f, Vec2f(0.3f, 0.8f));
    ASSERT_TRUE(bs.valid());
    EXPECT_GT(bs.pdf, 0.f);
    EXPECT_EQ(bs.weight[0], -0.5f);
    EXPECT_EQ(bs.weight[2], 0.f);
}

TEST(Conductor, PerfectMirrorReflectsEverythingExactly) {
    auto bsdf = make_bsdf<3>(props("conductor"));
    for (const Vec3f& wi : kUpper) {
        BSDFSample<3> bs = bsdf->sample({}, wi, 0.3f, Vec2f(0.1f, 0.9f));
        ASSERT_TRUE(bs.valid());
        EXPECT_EQ(bs.lobe, kDeltaReflection);
        EXPECT_LT((bs.wo - Vec3f(-wi.x(), -wi.y(), wi.z())).norm(), 1e-7f);
        EXPECT_EQ(albedo(*bsdf, wi, TransportMode::Radiance, 1000).mean, 1.0);
    }
    expect_weights(props("conductor"), kUpper, TransportMode::Radiance, 100);
}

TEST(Conductor, FresnelWeightedByComplexIOR) {
    Values gold = {{"eta", rgb(0.2f, 0.9f, 1.1f)}, {"k", rgb(3.9f, 2.4f, 2.2f)}, {"specular_reflectance", 0.5f}};
    auto bsdf = make_bsdf<3>(props("conductor", gold));
    Vec3f wi = dir(0.4f, 1.f);
    BSDFSample<3> bs = bsdf->sample({}, wi, 0.5f, Vec2f(0.5f, 0.5f));
    Spectrum<3> f = 0.5f * fresnel_conductor<3>(0.4f, Spectrum<3>(0.2f, 0.9f, 1.1f), Spectrum<3>(3.9f, 2.4f, 2.2f));
    EXPECT_LT((bs.weight - f).abs().maxCoeff(), 1e-6f);
    EXPECT_EQ(bsdf->eval({}, wi, bs.wo).abs().maxCoeff(), 0.f);
    EXPECT_EQ(bsdf->pdf({}, wi, bs.wo), 0.f);
}

TEST(RoughConductor, SampleMatchesPdfChi2) {
    for (const Props& p : rough_sets("roughconductor")) expect_chi2(p, kUpper);
}
TEST(RoughConductor, WeightMatchesEvalOverPdf) {
    for (const Props& p : rough_sets("roughconductor", {{"eta", rgb(0.2f, 0.9f, 1.1f)}, {"k", rgb(3.9f, 2.4f, 2.2f)}}))
        expect_weights(p, kUpper, TransportMode::Radiance);
}
TEST(RoughConductor, Reciprocity) {
    for (const Props& p : rough_sets("roughconductor", {{"eta", rgb(0.2f, 0.9f, 1.1f)}, {"k", rgb(3.9f, 2.4f, 2.2f)}}))
        expect_reciprocal(p, false);
}
// Lower bounds: single-scattering microfacet models lose energy to masking and to reflections
// below the horizon (GGX at alpha 0.7 keeps only ~50% at normal incidence).
double min_albedo(const Props& p, double a005, double a03, double a07) {
    float alpha = std::get<float>(p.values.at("alpha"));
    return alpha < 0.1f ? a005 : alpha < 0.5f ? a03 : a07;
}
TEST(RoughConductor, EnergyBounded) {
    for (const Props& p : rough_sets("roughconductor"))
        expect_energy(p, kUpper, TransportMode::Radiance, min_albedo(p, 0.95, 0.75, 0.4));
}

TEST(Dielectric, LobeFrequenciesMatchFresnelAndDirectionsObeySnell) {
    auto bsdf = make_bsdf<3>(props("dielectric", {{"int_ior", 1.5f}, {"ext_ior", 1.f}}));
    for (const Vec3f& wi : kBothSides) {
        FresnelDielectric f = fresnel_dielectric(wi.z(), 1.5f);
        Rng rng(9);
        const int n = 100000;
        int reflected = 0;
        for (int i = 0; i < n; ++i) {
            float u1 = rng.next();
            BSDFSample<3> bs = bsdf->sample({}, wi, u1, rng.next2());
            ASSERT_TRUE(bs.valid());
            if (bs.lobe == kDeltaReflection) {
                ++reflected;
                EXPECT_EQ(bs.pdf, f.R);
            } else {
                ASSERT_EQ(bs.lobe, kDeltaTransmission);
                EXPECT_NEAR(bs.wo.head<2>().norm() * bs.eta, wi.head<2>().norm(), 1e-5f);  // Snell
                EXPECT_LT(bs.wo.z() * wi.z(), 0.f);
            }
        }
        double se = std::sqrt(f.R * (1.0 - f.R) / n);  // binomial count, 4 sigma
        EXPECT_NEAR(double(reflected) / n, f.R, 4.0 * se + 1e-9) << "cos wi " << wi.z();
    }
}

TEST(Dielectric, ReflectPlusTransmitIsOneInImportanceMode) {
    auto bsdf = make_bsdf<3>(props("dielectric"));
    const float eta = 1.5046f / 1.000277f;
    for (const Vec3f& wi : kBothSides) {
        EXPECT_EQ(albedo(*bsdf, wi, TransportMode::Importance, 20000).mean, 1.0) << wi.z();
        // Radiance mode: refracted weight 1/eta^2 entering glass, eta^2 leaving it.
        BSDFSample<3> bs = bsdf->sample({}, wi, 0.999f, Vec2f(0.5f, 0.5f));
        if (bs.lobe == kDeltaTransmission) {
            EXPECT_NEAR(bs.weight[0], wi.z() > 0.f ? 1.f / (eta * eta) : eta * eta, 1e-5f);
        }
    }
}

TEST(RoughDielectric, SampleMatchesPdfChi2) {
    for (const Props& p : rough_sets("roughdielectric", {{"int_ior", 1.5f}, {"ext_ior", 1.f}}))
        expect_chi2(p, kBothSides);
}
TEST(RoughDielectric, WeightMatchesEvalOverPdf) {
    for (const Props& p : rough_sets("roughdielectric"))
        for (TransportMode mode : {TransportMode::Radiance, TransportMode::Importance})
            expect_weights(p, kBothSides, mode);
}
TEST(RoughDielectric, Reciprocity) {
    for (const Props& p : rough_sets("roughdielectric", {{"int_ior", 1.5f}, {"ext_ior", 1.f}}))
        expect_reciprocal(p, true, 1.5f);
}
TEST(RoughDielectric, EnergyBoundedInImportanceMode) {
    for (const Props& p : rough_sets("roughdielectric"))
        expect_energy(p, kBothSides, TransportMode::Importance, min_albedo(p, 0.9, 0.6, 0.3));
}

std::vector<Props> plastic_sets() {
    return {props("plastic"), props("plastic", {{"nonlinear", true}, {"int_ior", 1.9f}}),
            props("plastic", {{"diffuse_reflectance", rgb(0.9f, 0.1f, 0.4f)}, {"specular_reflectance", 0.7f}})};
}
TEST(Plastic, SampleMatchesPdfChi2) {
    for (const Props& p : plastic_sets()) expect_chi2(p, kUpper);
}
TEST(Plastic, WeightMatchesEvalOverPdf) {
    for (const Props& p : plastic_sets()) expect_weights(p, kUpper, TransportMode::Radiance);
}
TEST(Plastic, Reciprocity) {
    for (const Props& p : plastic_sets()) expect_reciprocal(p, false);
}
TEST(Plastic, WhiteConservesEnergy) {
    for (bool nonlinear : {false, true}) {
        auto bsdf = make_bsdf<3>(props("plastic", {{"diffuse_reflectance", 1.f}, {"nonlinear", nonlinear}}));
        for (const Vec3f& wi : kUpper) {
            Albedo a = albedo(*bsdf, wi, TransportMode::Radiance);
            EXPECT_NEAR(a.mean, 1.0, 3.0 * a.se + 1e-4) << "cos wi " << wi.z();
        }
    }
}

TEST(RoughPlastic, SampleMatchesPdfChi2) {
    for (const Props& p : rough_sets("roughplastic")) expect_chi2(p, kUpper);
}
TEST(RoughPlastic, WeightMatchesEvalOverPdf) {
    for (const Props& p : rough_sets("roughplastic", {{"nonlinear", true}}))
        expect_weights(p, kUpper, TransportMode::Radiance);
}
TEST(RoughPlastic, Reciprocity) {
    for (const Props& p : rough_sets("roughplastic", {{"diffuse_reflectance", rgb(0.9f, 0.1f, 0.4f)}}))
        expect_reciprocal(p, false);
}
/// Mitsuba 3's internal reflectance of a rough coating (roughplastic.cpp): 2 · mean over the 64
/// cosines μ_j = max(1e-6, j/63) of R(μ_j; 1/η) μ_j, the rough interface's reflectance seen from
/// the dense side. R is estimated here from the roughdielectric plugin's own sampling (reflected
/// samples only), independently of roughplastic's tables; returns the estimate and its 1σ.
std::pair<double, double> mitsuba_internal_reflectance(const std::string& distribution, float alpha, float eta) {
    auto inside = make_bsdf<3>(props(
        "roughdielectric", {{"distribution", distribution}, {"alpha", alpha}, {"int_ior", 1.f}, {"ext_ior", eta}}));
    const int n = 20000;
    double f = 0, var = 0;
    for (int j = 0; j < kTransmittanceRes; ++j) {
        const double mu = std::max(1e-6, double(j) / (kTransmittanceRes - 1));
        const Vec3f wi(float(std::sqrt(std::max(0.0, 1.0 - mu * mu))), 0.f, float(mu));
        Rng rng(17 + j);
        double sum = 0, sum2 = 0;
        for (int i = 0; i < n; ++i) {
            float u1 = rng.next();
            BSDFSample<3> bs = inside->sample(context(TransportMode::Radiance), wi, u1, rng.next2());
            const double w = bs.valid() && bs.wo.z() > 0.f ? double(bs.weight.mean()) : 0.0;
            sum += w, sum2 += w * w;
        }
        const double r = sum / n, r_var = std::max(0.0, sum2 / n - r * r) / (n - 1);
        f += r * mu;
        var += r_var * mu * mu;
    }
    const double scale = 2.0 / kTransmittanceRes;
    return {scale * f, scale * std::sqrt(var)};
}

TEST(RoughPlastic, WhiteAlbedoFollowsMitsubasInternalReflectance) {
    // White, nonlinear = false: albedo(μ) = A(μ) + t(μ) T̄ / (η² (1 − F_int)), A the specular
    // albedo, t the coating's transmittance (docs/bsdfs.md (25)-(27)). Mitsuba's F_int (a 64-point mean, ~1.5 % below
    // the integral, and the rough interface's own) is not the smooth identity 1 − T̄/η², which would make the white
    // plastic conserve energy exactly: the test tells the two apart by 1-5 % of the albedo.
    const float eta = 1.5f;
    for (const Props& p :
         rough_sets("roughplastic", {{"diffuse_reflectance", 1.f}, {"int_ior", eta}, {"ext_ior", 1.f}})) {
        const std::string distribution = std::get<std::string>(p.values.at("distribution"));
        const float alpha = std::get<float>(p.values.at("alpha"));
        const auto [f_int, f_sigma] = mitsuba_internal_reflectance(distribution, alpha, eta);
        const MicrofacetType type = distribution == "ggx" ? MicrofacetType::GGX : MicrofacetType::Beckmann;
        const TransmittanceTable table = rough_transmittance(type, eta, alpha),
                                 specular = rough_reflectance(type, eta, alpha);
        const double base = table.mean / (double(eta) * eta * (1.0 - f_int));
        for (const Vec3f& wi : kUpper) {
            const double t_i = interpolate_mu(table.t, wi.z()),
                         expected = interpolate_mu(specular.t, wi.z()) + t_i * base;
            const double expected_sigma = t_i * base / (1.0 - f_int) * f_sigma;
            Albedo a = albedo(*make_bsdf<3>(p), wi, TransportMode::Radiance);
            EXPECT_NEAR(a.mean, expected, 3.0 * std::hypot(a.se, expected_sigma) + 2e-3)
                << describe(p) << ", cos wi " << wi.z();
            EXPECT_LE(a.mean, 1.0 + 3.0 * a.se + 1e-5) << "passive: " << describe(p);
        }
    }
}

Props twosided(const Props& inner) {
    Props p = props("twosided");
    p.values["bsdf"] = std::make_shared<Props>(inner);
    return p;
}
TEST(TwoSided, BackFaceMirrorsFrontFace) {
    for (const Props& inner : {props("diffuse"), props("plastic"), rough_sets("roughconductor")[4]}) {
        auto one = make_bsdf<3>(inner), two = make_bsdf<3>(twosided(inner));
        Vec3f wi = dir(0.6f, 1.f), wo = dir(0.3f, 4.f);
        auto flip = [](Vec3f w) { return Vec3f(w.x(), w.y(), -w.z()); };
        EXPECT_EQ((two->eval({}, flip(wi), flip(wo)) - one->eval({}, wi, wo)).abs().maxCoeff(), 0.f);
        EXPECT_EQ(two->pdf({}, flip(wi), flip(wo)), one->pdf({}, wi, wo));
        BSDFSample<3> a = one->sample({}, wi, 0.4f, Vec2f(0.2f, 0.7f)),
                      b = two->sample({}, flip(wi), 0.4f, Vec2f(0.2f, 0.7f));
        EXPECT_EQ(b.wo, flip(a.wo));
        EXPECT_EQ(two->eval({}, wi, wo)[0], one->eval({}, wi, wo)[0]);  // front face unchanged
    }
}
TEST(TwoSided, SampleMatchesPdfChi2FromBelow) {
    std::vector<Vec3f> below = {dir(-0.9f, 1.f), dir(-0.3f, 3.f)};
    for (const Props& inner : {props("diffuse"), props("plastic"), rough_sets("roughplastic")[4]}) {
        expect_chi2(twosided(inner), below);
        expect_weights(twosided(inner), below, TransportMode::Radiance);
    }
}

TEST(TwoSided, EnergyBoundedOnBothFaces) {
    for (const Props& inner : {props("diffuse", {{"reflectance", 1.f}}),
                               props("plastic", {{"diffuse_reflectance", 1.f}}), rough_sets("roughconductor")[1]})
        expect_energy(twosided(inner), {dir(0.7f, 1.f), dir(-0.7f, 1.f), dir(-0.2f, 2.f)}, TransportMode::Radiance,
                      0.8);
}

// (e) registry errors name the offending field.
void expect_scene_error(const Props& p, const std::string& field, const std::string& text) {
    try {
        make_bsdf<3>(p);
        ADD_FAILURE() << "no SceneError for " << describe(p);
    } catch (const SceneError& e) {
        EXPECT_EQ(e.field(), field) << e.what();
        EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("'" + field + "'"), std::string::npos) << e.what();
    }
}
TEST(BSDFRegistry, UnknownTypeAndBadValuesNameTheField) {
    expect_scene_error(props("velvet"), "type", "known: diffuse, conductor");
    expect_scene_error(props("roughconductor", {{"alpha", -1.f}}), "alpha", "> 0");
    expect_scene_error(props("roughplastic", {{"distribution", std::string("phong")}}), "distribution", "phong");
    expect_scene_error(props("dielectric", {{"int_ior", -1.f}}), "int_ior", "> 0");
    expect_scene_error(props("plastic", {{"ext_ior", std::string("unobtainium")}}), "ext_ior", "unknown IOR");
    expect_scene_error(props("conductor", {{"material", std::string("Cu")}}), "material", "IOR database");
    expect_scene_error(props("twosided"), "bsdf", "nested");
    expect_scene_error(twosided(props("dielectric")), "bsdf", "reflection");
    Props nested = props("roughdielectric", {{"alpha", 0.f}});
    nested.where = "materials.glass";
    expect_scene_error(nested, "materials.glass.alpha", "alpha");
    EXPECT_NEAR(make_bsdf<3>(props("dielectric", {{"int_ior", std::string("water")}}))
                    ->sample({}, dir(1.f, 0.f), 0.f, Vec2f(0.f, 0.f))
                    .pdf,
                fresnel_dielectric(1.f, 1.333f / 1.000277f).R, 1e-6f);
}

// (f) sampling depends on geometry only; 16 channels carry the luminance-broadcast values.
std::vector<Props> all_types(const Values& colours) {
    std::vector<Props> out;
    for (const char* t :
         {"diffuse", "conductor", "roughconductor", "dielectric", "roughdielectric", "plastic", "roughplastic"})
        out.push_back(props(t, colours));
    out.push_back(twosided(props("roughplastic", colours)));
    return out;
}
TEST(BSDFSampling, IndependentOfSignedSpectralCoefficients) {
    Values a = {{"reflectance", rgb(0.5f, 0.5f, 0.5f)}, {"diffuse_reflectance", rgb(0.5f, 0.5f, 0.5f)}},
           b = {{"reflectance", rgb(-0.7f, 0.f, 3.f)},
                {"diffuse_reflectance", rgb(-0.7f, 0.f, 3.f)},
                {"specular_reflectance", rgb(-1.f, 0.f, 0.2f)},
                {"specular_transmittance", rgb(0.f, -2.f, 1.f)}};
    std::vector<Props> pa = all_types(a), pb = all_types(b);
    for (size_t i = 0; i < pa.size(); ++i) {
        auto x = make_bsdf<3>(pa[i]);
        auto y = make_bsdf<16>(pb[i]);
        Rng rng(13);
        for (int k = 0; k < 2000; ++k) {
            Vec3f wi = sample_uniform_sphere(rng.next2());
            float u1 = rng.next();
            Vec2f u2 = rng.next2();
            BSDFSample<3> s = x->sample({}, wi, u1, u2);
            BSDFSample<16> t = y->sample({}, wi, u1, u2);
            ASSERT_EQ(s.valid(), t.valid()) << describe(pb[i]);
            if (!s.valid()) continue;
            ASSERT_EQ(s.wo, t.wo) << describe(pb[i]);
            ASSERT_EQ(s.pdf, t.pdf) << describe(pb[i]);
            ASSERT_EQ(s.lobe, t.lobe) << describe(pb[i]);
            ASSERT_EQ(x->pdf({}, wi, s.wo), y->pdf({}, wi, s.wo)) << describe(pb[i]);
        }
    }
}

TEST(BSDFLatent, SixteenChannelsCarryLuminance) {
    Props p = props("roughplastic", {{"diffuse_reflectance", rgb(0.2f, 0.5f, 0.8f)}});
    Props q = props("roughplastic", {{"diffuse_reflectance", 0.2126f * 0.2f + 0.7152f * 0.5f + 0.0722f * 0.8f}});
    Vec3f wi = dir(0.8f, 0.f), wo = dir(0.5f, 2.f);
    Spectrum<16> f = make_bsdf<16>(p)->eval({}, wi, wo);
    float g = make_bsdf<3>(q)->eval({}, wi, wo)[1];
    for (int c = 0; c < 16; ++c) EXPECT_NEAR(f[c], g, 1e-6f);
}

// The tracer samples Lambertian vertices itself (batch-warped cosine directions) and weights them
// with lambertian_reflectance(): that must be exactly what the BSDF's own sample() returns, and
// no other BSDF may claim a Lambertian reflectance.
TEST(Lambertian, ReflectanceIsWhatSampleWeightsWith) {
    const Props diffuse = props("diffuse", {{"reflectance", rgb(0.3f, 0.6f, 0.9f)}});
    for (const Props& p : {diffuse, twosided(diffuse)}) {
        auto bsdf = make_bsdf<3>(p);
        ASSERT_NE(bsdf->lambertian(), Lambertian::No) << p.type;
        const BSDFContext ctx;
        for (float wz : {0.7f, -0.4f}) {
            const Vec3f wi = Vec3f(0.3f, -0.2f, wz).normalized();
            const Vec2f u(0.37f, 0.81f);
            const BSDFSample<3> own = bsdf->sample(ctx, wi, 0.5f, u);
            const BSDFSample<3> tracer = lambertian_sample<3>(bsdf->lambertian(), wi, sample_cosine_hemisphere(u),
                                                              bsdf->lambertian_reflectance(ctx));
            EXPECT_EQ(own.valid(), tracer.valid()) << p.type;
            if (!own.valid()) continue;
            EXPECT_TRUE((own.weight == tracer.weight).all()) << p.type;
            EXPECT_TRUE(own.wo.isApprox(tracer.wo)) << p.type;
        }
    }
    for (const char* type : {"conductor", "dielectric", "plastic", "roughconductor"}) {
        auto bsdf = make_bsdf<3>(props(type));
        EXPECT_EQ(bsdf->lambertian(), Lambertian::No) << type;
        EXPECT_TRUE((bsdf->lambertian_reflectance(BSDFContext{}) == 0.f).all()) << type;
    }
}

}  // namespace
}  // namespace lpt
