// BSDF checks against closed forms that need no other renderer (docs/validation.md (5)-(6)):
// conductor Fresnel against the complex-arithmetic Fresnel equations, and the rough plugins'
// white furnace converging to the smooth interface's reflectance as the roughness goes to 0.
#include "chi2.h"
#include "core/bsdf.h"
#include "core/bsdfs/fresnel.h"
#include <complex>

namespace lpt {
namespace {

using namespace lpt::test;
using cd = std::complex<double>;

/// Unpolarised reflectance of a vacuum / (eta + i k) interface from the Fresnel amplitude
/// coefficients in complex arithmetic (Born & Wolf): cos θt = sqrt(1 − sin²θi / n²),
/// r_s = (cos θi − n cos θt) / (cos θi + n cos θt), r_p = (n cos θi − cos θt) / (n cos θi + cos θt).
double fresnel_complex(double cos_i, double eta, double k) {
    const cd n(eta, k);
    const double sin2 = 1.0 - cos_i * cos_i;
    const cd cos_t = std::sqrt(1.0 - sin2 / (n * n));
    const cd rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
    const cd rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
    return 0.5 * (std::norm(rs) + std::norm(rp));
}

// veach-bidir's LampBSDF, gold-like, a weak absorber and Mitsuba's default (eta 0, k 1).
const std::vector<std::pair<Eigen::Array3f, Eigen::Array3f>> kConductors = {
    {{2.8656f, 2.11918f, 1.94008f}, {3.03233f, 2.05611f, 1.61629f}},
    {{0.2f, 0.9f, 1.1f}, {3.9f, 2.4f, 2.2f}},
    {{1.5f, 1.2f, 2.5f}, {0.01f, 0.3f, 0.05f}},
    {{0.f, 0.f, 0.f}, {1.f, 1.f, 1.f}},
};

TEST(ClosedForm, ConductorFresnelEqualsComplexFresnelEquations) {
    double worst = 0;
    for (const auto& [eta, k] : kConductors)
        for (int i = 0; i <= 200; ++i) {
            const float c = i == 0 ? 1e-4f : float(i) / 200.f;
            const Spectrum<3> f = fresnel_conductor<3>(c, Spectrum<3>(eta), Spectrum<3>(k));
            for (int ch = 0; ch < 3; ++ch) {
                const double exact = fresnel_complex(c, eta[ch], k[ch]);
                worst = std::max(worst, std::abs(f[ch] - exact));
                EXPECT_NEAR(f[ch], exact, 2e-5) << "eta " << eta[ch] << " k " << k[ch] << " cos " << c;
            }
        }
    std::cout << "conductor Fresnel vs complex Fresnel equations: worst |difference| " << worst << "\n";
}

/// Albedo of a BSDF split into reflected and transmitted parts (mean sample weight per lobe).
struct Split {
    double reflect = 0, transmit = 0;
};
Split albedo_split(const BSDF<3>& bsdf, const Vec3f& wi, TransportMode mode, int n = 200000) {
    BSDFContext ctx = context(mode);
    Rng rng(13);
    Split s;
    for (int i = 0; i < n; ++i) {
        float u1 = rng.next();
        BSDFSample<3> bs = bsdf.sample(ctx, wi, u1, rng.next2());
        if (!bs.valid()) continue;
        (bs.lobe & kTransmission ? s.transmit : s.reflect) += double(bs.weight.mean()) / n;
    }
    return s;
}

TEST(ClosedForm, RoughConductorFurnaceConvergesToSmoothFresnel) {
    // As alpha -> 0 the microfacet lobe becomes the mirror direction and masking vanishes, so
    // the albedo tends to the smooth conductor's F(cos θi) (Beckmann and GGX alike).
    for (const char* distr : {"beckmann", "ggx"})
        for (const auto& [eta, k] : kConductors)
            for (float cos_i : {0.9f, 0.5f, 0.2f}) {
                const Vec3f wi = dir(cos_i, 0.7f);
                const double smooth = fresnel_conductor<3>(cos_i, Spectrum<3>(eta), Spectrum<3>(k)).mean();
                double previous = 1e9;
                for (float alpha : {0.1f, 0.01f, 0.001f}) {
                    auto bsdf = make_bsdf<3>(props("roughconductor", {{"distribution", std::string(distr)},
                                                                      {"alpha", alpha},
                                                                      {"eta", Eigen::Array3f(eta)},
                                                                      {"k", Eigen::Array3f(k)}}));
                    const double gap = std::abs(albedo_split(*bsdf, wi, TransportMode::Radiance).reflect - smooth);
                    if (alpha < 0.05f) {
                        EXPECT_LE(gap, previous + 1e-4) << distr << " alpha " << alpha << " cos " << cos_i;
                    }
                    previous = gap;
                }
                EXPECT_LT(previous, 2e-3) << distr << " eta " << eta.transpose() << " cos " << cos_i
                                          << ": alpha 0.001 albedo off by " << previous;
            }
}

TEST(ClosedForm, RoughDielectricFurnaceConvergesToSmoothInterface) {
    // In importance mode a smooth dielectric reflects R(cos θi) and transmits 1 − R with no
    // 1/eta² factor; the rough one must approach both parts, from either side.
    const float eta = 1.5f;
    for (const char* distr : {"beckmann", "ggx"})
        for (float cos_i : {0.9f, 0.5f, -0.9f, -0.5f}) {
            const Vec3f wi = dir(cos_i, 1.1f);
            const double R = fresnel_dielectric(cos_i, eta).R;
            auto bsdf = make_bsdf<3>(
                props("roughdielectric",
                      {{"distribution", std::string(distr)}, {"alpha", 0.001f}, {"int_ior", eta}, {"ext_ior", 1.f}}));
            const Split s = albedo_split(*bsdf, wi, TransportMode::Importance);
            EXPECT_NEAR(s.reflect + s.transmit, 1.0, 2e-3) << distr << " cos " << cos_i;
            EXPECT_NEAR(s.reflect, R, 3e-3) << distr << " cos " << cos_i;
        }
}

}  // namespace
}  // namespace lpt
