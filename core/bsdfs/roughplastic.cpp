// "roughplastic": rough dielectric coating over a Lambertian base (Mitsuba 3's roughplastic):
// a microfacet specular lobe plus a diffuse lobe attenuated by the coating's rough transmittance
// t(mu) (the refracted energy at incidence mu, as Mitsuba's eval_transmittance) on the way in
// and out. One-sided.
// Keys: diffuse_reflectance (rgb, default 0.5); specular_reflectance (rgb, default 1);
// distribution ("beckmann" | "ggx", default beckmann); alpha (float, default 0.1, > 0);
// int_ior (default 1.49 = polypropylene), ext_ior (default 1.000277 = air), > 0 and distinct;
// nonlinear (bool, default false).
// Deviations from Mitsuba 3: lobe choice by the rough Fresnel albedo only (Mitsuba also weighs
// by mean reflectances, signed in latent space); t(mu) is tabulated (64 entries, as Mitsuba)
// by a stratified microfacet-sampling quadrature instead of Gauss-Lobatto.
// The internal reflectance is Mitsuba's: 2 * mean_j A(mu_j; 1/eta) mu_j over the 64 table
// cosines. It is not the smooth identity 1 - T/eta^2, so a white roughplastic loses 1-5 % of
// its energy as in Mitsuba; with the identity, dining-room rendered 2.3 % brighter than a Cycles
// translation of Mitsuba's model (docs/validation.md).
// Gradients w.r.t. the diffuse colour (keys below the substrate's key_count, as plastic.cpp) and
// specular_reflectance (the last key): docs/bsdfs.md
// (34), (36); with nonlinear = true the base colour is not affine in diffuse_reflectance.
// Scalar key "alpha" (roughness): set_scalar re-derives the t(mu) table, Fdr_int and the base
// colour; ∂/∂α covers the specular lobe AND the diffuse lobe's α-dependence through t(cos θi),
// t(cos θo) and Fdr_int. The tables come from rough_transmittance.h: cached nodes in ln α,
// interpolated, so a set_scalar costs microseconds and ∂t/∂α is the exact derivative of the t
// that eval uses: docs/bsdfs.md (42)-(43), (46).
// cycles_approximation (bool, validation only; core/bsdfs/cycles_approximation.h): t(cos θo) by
// T̄, and the specular Fresnel by R(cos θi)/A_glossy(cos θi) at the macro normal.
// Equations: docs/bsdfs.md (7)-(10), (12), (25)-(28), (34), (36)-(39), (42)-(43), (46), (49).
#include "core/bsdfs/cycles_approximation.h"
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/microfacet_bsdf.h"
#include "core/bsdfs/plastic_substrate.h"
#include "core/bsdfs/rough_transmittance.h"
#include "core/warp.h"
#include <algorithm>

namespace lpt {
namespace {

template <int N>
class RoughPlastic final : public MicrofacetBSDF<N> {
public:
    explicit RoughPlastic(const Props& props)
        : MicrofacetBSDF<N>(props),
          m_eta(read_relative_ior(props, 1.49f, 1.000277f, true)),
          m_substrate(props),
          m_specular(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))),
          m_cycles_approximation(read_cycles_approximation<N>(props)) {
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

    Spectrum<N> eval(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const override {
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float spec = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_i);  // docs/bsdfs.md (25)
        if (spec != 0.f) spec *= specular_fresnel(wi, h);
        float diff = m_inv_eta2 * transmittance(cos_i) * transmittance_out(cos_o) * kInvPi * cos_o;
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
            return m_substrate.d_base(ctx, key) *
                   (m_inv_eta2 * transmittance(cos_i) * transmittance_out(cos_o) * kInvPi * cos_o);
        Vec3f h = (wi + wo).normalized();
        float spec = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_i);
        if (spec != 0.f) spec *= specular_fresnel(wi, h);
        return Spectrum<N>::Constant(spec);
    }

    /// ∂(f·|cos wo|)/∂α, docs/bsdfs.md (42), from (25) by the product rule:
    ///   specular_reflectance · R(wi·h) (∂D G + D ∂G) / (4 cos θi)                (37)-(39)
    ///   + (1/η²)(cos θo/π) [∂ρ̃/∂α t_i t_o + ρ̃ (∂t_i t_o + t_i ∂t_o)],
    /// with ∂t/∂α interpolated from its own table exactly as t is (the interpolation weights do
    /// not depend on α) and ∂ρ̃/∂α from ∂Fdr_int/∂α = −(∂T̄/∂α)/η² (27), (34). The ∂t/∂α table
    /// is the α-derivative of the interpolated t table (46), so this is the exact derivative of
    /// eval (tests/core/bsdfs/test_bsdf_alpha.cpp).
    /// weight_grad_scalar keeps the base-class default: sample() returns exactly eval/pdf (28)
    /// and path replay holds bs.wo and bs.pdf fixed (docs/bsdfs.md (43)).
    Spectrum<N> eval_grad_scalar(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        if (key != 0) throw std::invalid_argument("roughplastic: scalar key index out of range");
        if (m_cycles_approximation)  // the R/A table's own α-derivative is not tabulated
            throw std::logic_error("roughplastic: cycles_approximation has no roughness derivative");
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float dspec = m_distr.dDG_dalpha(wi, wo, h) / (4.f * cos_i);
        if (dspec != 0.f) dspec *= fresnel_dielectric(wi.dot(h), m_eta).R;
        float t_i = transmittance(cos_i), t_o = transmittance(cos_o);
        float dt_i = interpolate_mu(m_tables.dt, cos_i), dt_o = interpolate_mu(m_tables.dt, cos_o);
        float k = m_inv_eta2 * kInvPi * cos_o;
        return m_specular * dspec + m_substrate.d_base_d_alpha(ctx) * (k * t_i * t_o) +
               m_substrate.base(ctx) * (k * (dt_i * t_o + t_i * dt_o));
    }

private:
    /// set_scalar("alpha") rebuilds everything derived from alpha: t(mu) and ∂t/∂α tables,
    /// Fdr_int, ρ̃ and their α-derivatives. Interpolates cached tables (docs/bsdfs.md (46)):
    /// microseconds, plus 40–90 ms for each node α not met before.
    void alpha_changed() override { rebuild(); }

    // Everything derived from alpha: t and ∂t/∂α (26), (46), Fdr_int and its α-derivative (27), ρ̃.
    void rebuild() {
        m_tables = rough_transmittance(m_distr.type(), m_eta, m_distr.alpha());
        // docs/bsdfs.md (27), (42): Mitsuba 3's internal reflectance, the 64-point mean
        // 2 · mean_j A(μ_j; 1/η) μ_j of the coating's specular albedo seen from inside.
        const TransmittanceTable inside = rough_reflectance(m_distr.type(), 1.f / m_eta, m_distr.alpha());
        double f = 0.0, df = 0.0;
        for (int j = 0; j < kTransmittanceRes; ++j) {
            const double mu = std::max(1e-6, double(j) / (kTransmittanceRes - 1));
            f += inside.t[j] * mu;
            df += inside.dt[j] * mu;
        }
        m_substrate.set_internal_reflectance(float(2.0 * f / kTransmittanceRes), float(2.0 * df / kTransmittanceRes));
        if (m_cycles_approximation) rebuild_cycles_ratio();
    }
    // docs/bsdfs.md (49): R(μ_j) / A_glossy(μ_j), the factor that gives a Fresnel-free lobe
    // Mitsuba's specular albedo; μ_0 = 0 takes μ_1's value, as the translation does. From the
    // cached tables (46), as t: their interpolation in α is within 3e-4 of a fresh quadrature.
    void rebuild_cycles_ratio() {
        const TransmittanceTable r = rough_lobe_table(m_distr.type(), m_eta, m_distr.alpha(), CoatingLobe::Reflection);
        const TransmittanceTable a = rough_lobe_table(m_distr.type(), m_eta, m_distr.alpha(), CoatingLobe::Glossy);
        for (int j = 0; j < kTransmittanceRes; ++j) m_cycles_ratio[j] = a.t[j] > 1e-6f ? r.t[j] / a.t[j] : 0.f;
        m_cycles_ratio[0] = m_cycles_ratio[1];
    }
    float transmittance(float mu) const { return interpolate_mu(m_tables.t, mu); }
    /// t(cos θo), or its cosine-weighted mean T̄ under cycles_approximation (docs/bsdfs.md (49)).
    float transmittance_out(float cos_o) const { return m_cycles_approximation ? m_tables.mean : transmittance(cos_o); }
    /// R(wi·h), or R(μ_i)/A_glossy(μ_i) at the macro normal under cycles_approximation.
    float specular_fresnel(const Vec3f& wi, const Vec3f& h) const {
        return m_cycles_approximation ? interpolate_mu(m_cycles_ratio, cos_theta(wi))
                                      : fresnel_dielectric(wi.dot(h), m_eta).R;
    }

    using MicrofacetBSDF<N>::m_distr;
    float m_eta, m_inv_eta2 = 1.f;
    PlasticSubstrate<N> m_substrate;  ///< ρ̃ after internal bounces, docs/bsdfs.md (23)
    Spectrum<N> m_specular;
    TransmittanceTable m_tables;  ///< t(mu_j), ∂t/∂α(mu_j), T̄, ∂T̄/∂α at the current alpha
    bool m_cycles_approximation;
    std::array<float, kTransmittanceRes> m_cycles_ratio{};  ///< R/A_glossy, only with cycles_approximation
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_roughplastic_bsdf(const Props& props) {
    return std::make_unique<RoughPlastic<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_roughplastic_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_roughplastic_bsdf<16>(const Props&);

}  // namespace lpt
