// "roughplastic": rough dielectric coating over a Lambertian base (Mitsuba 3's roughplastic):
// a microfacet specular lobe plus a diffuse lobe attenuated by the coating's rough transmittance
// t(mu) = 1 - (specular albedo at incidence mu) on the way in and out. One-sided.
// Keys: diffuse_reflectance (rgb, default 0.5); specular_reflectance (rgb, default 1);
// distribution ("beckmann" | "ggx", default beckmann); alpha (float, default 0.1, > 0);
// int_ior (default 1.49 = polypropylene), ext_ior (default 1.000277 = air), > 0 and distinct;
// nonlinear (bool, default false).
// Deviations from Mitsuba 3: lobe choice by the rough Fresnel albedo only (Mitsuba also weighs
// by mean reflectances, signed in latent space); t(mu) is tabulated (64 entries, as Mitsuba)
// by a stratified microfacet-sampling quadrature instead of Gauss-Lobatto; the internal
// reflectance comes from the smooth-interface identity 1 - Fdr_int = (1 - Fdr_ext)/eta^2
// applied to the rough table (Mitsuba integrates the internal rough reflectance separately),
// which makes a white roughplastic conserve energy up to the table's accuracy (~1e-3): the
// base receives exactly what the rough coating does not reflect.
// Gradients w.r.t. the diffuse colour (keys below the substrate's key_count, as plastic.cpp) and
// specular_reflectance (the last key): docs/bsdfs.md
// (34), (36); with nonlinear = true the base colour is not affine in diffuse_reflectance.
// Scalar key "alpha" (roughness): set_scalar rebuilds the t(mu) table, Fdr_int and the base
// colour; ∂/∂α covers the specular lobe AND the diffuse lobe's α-dependence through t(cos θi),
// t(cos θo) and Fdr_int, via a second table ∂t/∂α built alongside t: docs/bsdfs.md (42)-(43).
// Equations: docs/bsdfs.md (7)-(10), (12), (25)-(28), (34), (36)-(39), (42)-(43).
#include "core/bsdf.h"
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/plastic_substrate.h"
#include "core/bsdfs/microfacet.h"
#include "core/warp.h"
#include <optional>
#include <algorithm>
#include <array>

namespace lpt {
namespace {

constexpr int kTableRes = 64;

template <int N>
class RoughPlastic final : public BSDF<N> {
public:
    explicit RoughPlastic(const Props& props)
        : m_distr(read_distribution(props), read_alpha(props)),
          m_eta(read_relative_ior(props, 1.49f, 1.000277f, true)),
          m_substrate(props),
          m_specular(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))) {
        m_inv_eta2 = 1.f / (m_eta * m_eta);
        rebuild();
    }

    /// The substrate colour's keys (diffuse_reflectance, or .scale/.offset when latent-textured),
    /// then specular_reflectance: key indices below m_substrate.key_count() are the colour's.
    std::vector<std::string> spectral_keys() const override {
        std::vector<std::string> k = m_substrate.keys();
        k.push_back("specular_reflectance");
        return k;
    }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key == "specular_reflectance") m_specular = v;
        else if (!m_substrate.set(key, v)) BSDF<N>::set_spectral(key, v);
    }

    std::vector<std::string> scalar_keys() const override { return {"alpha"}; }
    float get_scalar(const std::string& key) const override {
        if (key != "alpha") return BSDF<N>::get_scalar(key);
        return m_distr.alpha();
    }
    /// Raised to MicrofacetDistribution::kMinAlpha (1e-4) as at construction, then everything
    /// derived from alpha is rebuilt: t(mu) and ∂t/∂α tables, Fdr_int, ρ̃ and their
    /// α-derivatives (~6 ms GGX, ~10 ms Beckmann; skipped when the clamped value is unchanged).
    /// Non-finite values throw std::invalid_argument.
    void set_scalar(const std::string& key, float value) override {
        if (key != "alpha") BSDF<N>::set_scalar(key, value);
        float old = m_distr.alpha();
        m_distr.set_alpha(value);
        if (m_distr.alpha() != old) rebuild();  // the tables depend on alpha only
    }

    Spectrum<N> eval(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const override {
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float spec = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_i);  // docs/bsdfs.md (25)
        if (spec != 0.f) spec *= fresnel_dielectric(wi.dot(h), m_eta).R;
        float diff = m_inv_eta2 * transmittance(cos_i) * transmittance(cos_o) * kInvPi * cos_o;
        return m_specular * spec + m_substrate.base(ctx) * diff;
    }

    float pdf(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return 0.f;
        float p_diffuse = transmittance(cos_i);  // docs/bsdfs.md (28)
        Vec3f h = (wi + wo).normalized();
        float p_spec = m_distr.pdf(wi, h) / (4.f * wo.dot(h));
        return (1.f - p_diffuse) * p_spec + p_diffuse * pdf_cosine_hemisphere(wo);
    }

    BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float u1, const Vec2f& u2) const override {
        BSDFSample<N> bs;
        if (cos_theta(wi) <= 0.f) return bs;
        bool specular = u1 >= transmittance(cos_theta(wi));
        Vec3f wo;
        if (specular) {
            Vec3f m = m_distr.sample(wi, u2);
            // A back-facing microfacet (classic Beckmann sampling) yields no valid direction;
            // pdf() accounts only for front-facing ones, so it must be a failed sample.
            if (wi.dot(m) <= 0.f) return bs;
            wo = reflect(wi, m);
        } else {
            wo = sample_cosine_hemisphere(u2);
        }
        if (cos_theta(wo) <= 0.f) return bs;
        // One-sample MIS over both lobes (as Mitsuba): weight = full f cos / full pdf.
        float pdf = this->pdf(ctx, wi, wo);
        if (!(pdf > 0.f) || !std::isfinite(pdf)) return bs;
        bs.wo = wo;
        bs.pdf = pdf;
        bs.lobe = specular ? kGlossyReflection : kDiffuseReflection;
        bs.weight = eval(ctx, wi, wo) / pdf;
        return bs;
    }

    uint32_t flags() const override { return kGlossyReflection | kDiffuseReflection; }
    Spectrum<N> albedo(const BSDFContext& ctx) const override { return m_substrate.albedo(ctx); }

    /// ∂(f·|cos wo|)/∂c, docs/bsdfs.md (36). Key 0 (diffuse_reflectance): the diffuse term of
    /// (25) with ρ̃ replaced by ∂ρ̃/∂ρ from (34): a constant for nonlinear = false, but
    /// 1/(1 − ρ Fdr_int)² for nonlinear = true, so there it depends on the current diffuse
    /// reflectance. Key 1 (specular_reflectance): the specular term of (25) without the colour.
    /// weight_grad keeps the base-class default: sample() returns exactly eval/pdf (28) with a
    /// coefficient-independent pdf, so ∂weight/∂c = eval_grad/pdf.
    Spectrum<N> eval_grad(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return Spectrum<N>::Zero();
        if (key < m_substrate.key_count())
            return m_substrate.d_base(ctx, key) * (m_inv_eta2 * transmittance(cos_i) * transmittance(cos_o) * kInvPi * cos_o);
        Vec3f h = (wi + wo).normalized();
        float spec = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_i);
        if (spec != 0.f) spec *= fresnel_dielectric(wi.dot(h), m_eta).R;
        return Spectrum<N>::Constant(spec);
    }

    /// ∂(f·|cos wo|)/∂α, docs/bsdfs.md (42), from (25) by the product rule:
    ///   specular_reflectance · R(wi·h) (∂D G + D ∂G) / (4 cos θi)                (37)-(39)
    ///   + (1/η²)(cos θo/π) [∂ρ̃/∂α t_i t_o + ρ̃ (∂t_i t_o + t_i ∂t_o)],
    /// with ∂t/∂α interpolated from its own table exactly as t is (the interpolation weights do
    /// not depend on α) and ∂ρ̃/∂α from ∂Fdr_int/∂α = −(∂T̄/∂α)/η² (27), (34). The ∂t/∂α table
    /// is a quadrature of the exact derivative integral, not the derivative of t's quadrature:
    /// the two agree to the tables' accuracy (measured in tests/core/bsdfs/test_bsdf_alpha.cpp).
    /// weight_grad_scalar keeps the base-class default: sample() returns exactly eval/pdf (28)
    /// and path replay holds bs.wo and bs.pdf fixed (docs/bsdfs.md (43)).
    Spectrum<N> eval_grad_scalar(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        if (key != 0) throw std::invalid_argument("roughplastic: scalar key index out of range");
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float dspec = m_distr.dDG_dalpha(wi, wo, h) / (4.f * cos_i);
        if (dspec != 0.f) dspec *= fresnel_dielectric(wi.dot(h), m_eta).R;
        float t_i = transmittance(cos_i), t_o = transmittance(cos_o);
        float dt_i = interpolate(m_dtable, cos_i), dt_o = interpolate(m_dtable, cos_o);
        float k = m_inv_eta2 * kInvPi * cos_o;
        return m_specular * dspec + m_substrate.d_base_d_alpha(ctx) * (k * t_i * t_o) + m_substrate.base(ctx) * (k * (dt_i * t_o + t_i * dt_o));
    }

private:
    // Everything derived from alpha: t and ∂t/∂α (26), Fdr_int and its α-derivative (27), ρ̃.
    void rebuild() {
        auto [mean_t, dmean_t] = build_table();
        // docs/bsdfs.md (27), (42)
        m_substrate.set_internal_reflectance(1.f - mean_t * m_inv_eta2, -dmean_t * m_inv_eta2);
    }


    // Linear interpolation over mu = j / (kTableRes - 1), as Mitsuba's lerp_gather.
    static float interpolate(const std::array<float, kTableRes>& table, float mu) {
        float x = std::clamp(mu, 0.f, 1.f) * (kTableRes - 1);
        int j = std::min(int(x), kTableRes - 2);
        float w = x - float(j);
        return (1.f - w) * table[j] + w * table[j + 1];
    }
    float transmittance(float mu) const { return interpolate(m_table, mu); }

    // Tabulates t(mu) = 1 - A(mu), A the specular albedo with F (docs/bsdfs.md (26)), by a
    // midpoint grid over the microfacet sampler's unit square (smooth in u, so O(K^-2)), and
    // ∂t/∂α = -∂A/∂α (docs/bsdfs.md (42)) by a quadrature of the exact derivative integral.
    // Returns T̄ = 2 ∫ t(mu) mu dmu of the interpolated table, integrated exactly, and ∂T̄/∂α
    // (the same linear functional of the ∂t/∂α table).
    std::pair<float, float> build_table() {
        constexpr int K = 32;
        for (int j = 0; j < kTableRes; ++j) {
            float mu = std::max(1e-6f, float(j) / (kTableRes - 1));
            Vec3f wi(std::sqrt(std::max(0.f, 1.f - mu * mu)), 0.f, mu);
            double sum = 0.0;
            for (int a = 0; a < K; ++a)
                for (int b = 0; b < K; ++b) {
                    Vec3f m = m_distr.sample(wi, Vec2f((a + 0.5f) / K, (b + 0.5f) / K));
                    Vec3f wo = reflect(wi, m);
                    if (wo.z() <= 0.f) continue;
                    sum += fresnel_dielectric(wi.dot(m), m_eta).R * m_distr.sample_weight(wi, wo, m);
                }
            float t = 1.f - float(sum / (K * K));
            m_table[j] = std::clamp(t, 0.f, 1.f);
            // A clamped entry is locally constant in α.
            m_dtable[j] = t == m_table[j] ? -float(dalbedo_dalpha(wi)) : 0.f;
        }
        return {float(mean_cosine_weighted(m_table)), float(mean_cosine_weighted(m_dtable))};
    }

    // ∂A/∂α at incidence wi (docs/bsdfs.md (42)): ∫ R(wi·h) ∂(D G)/∂α / (4 mu) dωo over the
    // upper hemisphere, with the directions held fixed (only the integrand moves with α),
    // importance-sampled by the microfacet sampler at the current α over a midpoint grid:
    // E_u[R (∂D G + D ∂G)(wo·m) / (mu p(m | wi))], p(m | wi) from (8)/(9), the reflection
    // Jacobian (10) turning p(m) into p(wo). For Beckmann, d ln D/dα = 2 (tan²θm/α² - 1)/α
    // grows like -ln(1 - u1) toward u1 = 1, which a midpoint rule integrates poorly; there
    // u1 = 1 - (1 - v)², du1 = 2 (1 - v) dv smooths the endpoint ((1 - v) ln(1 - v) → 0).
    double dalbedo_dalpha(const Vec3f& wi) const {
        constexpr int K = 32;
        const bool beckmann = m_distr.type() == MicrofacetType::Beckmann;
        double mu = wi.z(), sum = 0.0;
        for (int a = 0; a < K; ++a) {
            double v = (a + 0.5) / K, u1 = v, jac = 1.0;
            if (beckmann) u1 = 1.0 - (1.0 - v) * (1.0 - v), jac = 2.0 * (1.0 - v);
            for (int b = 0; b < K; ++b) {
                Vec3f m = m_distr.sample(wi, Vec2f(float(u1), (b + 0.5f) / K));
                Vec3f wo = reflect(wi, m);
                float wo_m = wo.dot(m);
                if (wo.z() <= 0.f || wo_m <= 0.f) continue;
                double pm = m_distr.pdf(wi, m);
                if (!(pm > 0.0)) continue;
                double dDG = m_distr.dDG_dalpha(wi, wo, m);
                sum += jac * fresnel_dielectric(wi.dot(m), m_eta).R * dDG * wo_m / (mu * pm);
            }
        }
        return sum / (K * K);
    }

    // Exact ∫ (linear segment) 2 mu dmu of a table, per segment [m0, m1] with values t0, t1.
    static double mean_cosine_weighted(const std::array<float, kTableRes>& table) {
        double total = 0.0, h = 1.0 / (kTableRes - 1);
        for (int j = 0; j + 1 < kTableRes; ++j) {
            double m0 = j * h, m1 = m0 + h, t0 = table[j], t1 = table[j + 1];
            double slope = (t1 - t0) / h;
            double c = t0 - slope * m0;  // t = c + slope * mu
            total += c * (m1 * m1 - m0 * m0) + slope * 2.0 / 3.0 * (m1 * m1 * m1 - m0 * m0 * m0);
        }
        return total;
    }

    MicrofacetDistribution m_distr;
    float m_eta, m_inv_eta2 = 1.f;
    PlasticSubstrate<N> m_substrate;  ///< ρ̃ after internal bounces, docs/bsdfs.md (23)
    Spectrum<N> m_specular;
    std::array<float, kTableRes> m_table{}, m_dtable{};  ///< t(mu_j) and ∂t/∂α(mu_j)
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_roughplastic_bsdf(const Props& props) {
    return std::make_unique<RoughPlastic<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_roughplastic_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_roughplastic_bsdf<16>(const Props&);

}  // namespace lpt
