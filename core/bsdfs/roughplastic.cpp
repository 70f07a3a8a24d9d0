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
// Gradients w.r.t. diffuse_reflectance (key 0) and specular_reflectance (key 1): docs/bsdfs.md
// (34), (36); with nonlinear = true the base colour is not affine in diffuse_reflectance.
// Equations: docs/bsdfs.md (7)-(10), (12), (25)-(28), (34), (36).
#include "core/bsdf.h"
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/microfacet.h"
#include "core/warp.h"
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
          m_diffuse(spectrum_from_rgb<N>(props.get_rgb("diffuse_reflectance", Eigen::Array3f::Constant(0.5f)))),
          m_specular(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))) {
        m_inv_eta2 = 1.f / (m_eta * m_eta);
        m_nonlinear = props.get_bool("nonlinear", false);
        float mean_t = build_table();
        m_fdr_int = 1.f - mean_t * m_inv_eta2;  // docs/bsdfs.md (27)
        update_base();
    }

    std::vector<std::string> spectral_keys() const override { return {"diffuse_reflectance", "specular_reflectance"}; }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key == "diffuse_reflectance") m_diffuse = v, update_base();
        else if (key == "specular_reflectance") m_specular = v;
        else BSDF<N>::set_spectral(key, v);
    }

    Spectrum<N> eval(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float spec = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_i);  // docs/bsdfs.md (25)
        if (spec != 0.f) spec *= fresnel_dielectric(wi.dot(h), m_eta).R;
        float diff = m_inv_eta2 * transmittance(cos_i) * transmittance(cos_o) * kInvPi * cos_o;
        return m_specular * spec + m_base * diff;
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
    Spectrum<N> albedo(const BSDFContext&) const override { return m_diffuse; }

    /// ∂(f·|cos wo|)/∂c, docs/bsdfs.md (36). Key 0 (diffuse_reflectance): the diffuse term of
    /// (25) with ρ̃ replaced by ∂ρ̃/∂ρ from (34): a constant for nonlinear = false, but
    /// 1/(1 − ρ Fdr_int)² for nonlinear = true, so there it depends on the current diffuse
    /// reflectance. Key 1 (specular_reflectance): the specular term of (25) without the colour.
    /// weight_grad keeps the base-class default: sample() returns exactly eval/pdf (28) with a
    /// coefficient-independent pdf, so ∂weight/∂c = eval_grad/pdf.
    Spectrum<N> eval_grad(const BSDFContext&, const Vec3f& wi, const Vec3f& wo, int key) const override {
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i <= 0.f || cos_o <= 0.f) return Spectrum<N>::Zero();
        if (key == 0)
            return m_base_grad * (m_inv_eta2 * transmittance(cos_i) * transmittance(cos_o) * kInvPi * cos_o);
        Vec3f h = (wi + wo).normalized();
        float spec = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_i);
        if (spec != 0.f) spec *= fresnel_dielectric(wi.dot(h), m_eta).R;
        return Spectrum<N>::Constant(spec);
    }

private:
    // ρ̃ and ∂ρ̃/∂ρ, docs/bsdfs.md (25), (34).
    void update_base() {
        if (m_nonlinear) {
            Spectrum<N> denom = 1.f - m_diffuse * m_fdr_int;
            m_base = m_diffuse / denom;
            m_base_grad = 1.f / (denom * denom);
        } else {
            m_base = m_diffuse / (1.f - m_fdr_int);
            m_base_grad = Spectrum<N>::Constant(1.f / (1.f - m_fdr_int));
        }
    }

    // t(mu) by linear interpolation over mu = j / (kTableRes - 1), as Mitsuba's lerp_gather.
    float transmittance(float mu) const {
        float x = std::clamp(mu, 0.f, 1.f) * (kTableRes - 1);
        int j = std::min(int(x), kTableRes - 2);
        float w = x - float(j);
        return (1.f - w) * m_table[j] + w * m_table[j + 1];
    }

    // Tabulates t(mu) = 1 - A(mu), A the specular albedo with F (docs/bsdfs.md (26)), by a
    // midpoint grid over the microfacet sampler's unit square (smooth in u, so O(K^-2)).
    // Returns 2 ∫ t(mu) mu dmu of the interpolated table, integrated exactly.
    float build_table() {
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
            m_table[j] = std::clamp(1.f - float(sum / (K * K)), 0.f, 1.f);
        }
        // Exact ∫ (linear segment) * 2 mu dmu per segment [m0, m1] with values t0, t1.
        double total = 0.0, h = 1.0 / (kTableRes - 1);
        for (int j = 0; j + 1 < kTableRes; ++j) {
            double m0 = j * h, m1 = m0 + h, t0 = m_table[j], t1 = m_table[j + 1];
            double slope = (t1 - t0) / h;
            double c = t0 - slope * m0;  // t = c + slope * mu
            total += c * (m1 * m1 - m0 * m0) + slope * 2.0 / 3.0 * (m1 * m1 * m1 - m0 * m0 * m0);
        }
        return float(total);
    }

    MicrofacetDistribution m_distr;
    float m_eta, m_inv_eta2 = 1.f, m_fdr_int = 0.f;
    bool m_nonlinear = false;
    Spectrum<N> m_diffuse, m_specular, m_base, m_base_grad;
    std::array<float, kTableRes> m_table{};
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_roughplastic_bsdf(const Props& props) {
    return std::make_unique<RoughPlastic<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_roughplastic_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_roughplastic_bsdf<16>(const Props&);

}  // namespace lpt
