// "plastic": smooth dielectric coating over a Lambertian base (Mitsuba 3's plastic): a delta
// specular reflection off the coating plus a diffuse lobe that pays Fresnel transmission on the
// way in and out and accounts for light bouncing between the base and the coating's underside.
// One-sided (zero unless cos wi > 0).
// Keys: diffuse_reflectance (rgb, default 0.5); specular_reflectance (rgb, default 1);
// int_ior (default 1.49 = polypropylene, Mitsuba 3's plastic default), ext_ior (default
// 1.000277 = air), both > 0; nonlinear (bool, default false: internal bounces do not change the
// base colour's hue, Mitsuba's default).
// Deviations from Mitsuba 3: the specular-vs-diffuse choice uses the Fresnel reflectance only
// (Mitsuba also weighs by mean reflectances, which are signed in latent space); the diffuse
// Fresnel reflectance is integrated numerically instead of Mitsuba's polynomial fits (they
// differ by < 0.2% for 1.2 <= IOR <= 2), which makes a white plastic conserve energy exactly.
// Gradients w.r.t. the diffuse colour (keys below the substrate's key_count: diffuse_reflectance, or its
// .scale/.offset when latent-textured, ∂ρ̃/∂c = ∂ρ̃/∂ρ · ∂ρ/∂c) and specular_reflectance (the last key): docs/bsdfs.md
// (34)-(35); with nonlinear = true the base colour is not affine in diffuse_reflectance.
// cycles_approximation (bool, validation only): 1 − R(cos θo) by its cosine-weighted mean,
// core/bsdfs/cycles_approximation.h.
// Equations: docs/bsdfs.md (1), (4), (22)-(24), (34)-(35), (48).
#include "core/bsdf.h"
#include "core/bsdfs/cycles_approximation.h"
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/plastic_substrate.h"
#include "core/warp.h"
#include <optional>

namespace lpt {
namespace {

template <int N>
class SmoothPlastic final : public BSDF<N> {
public:
    explicit SmoothPlastic(const Props& props)
        : m_eta(read_relative_ior(props, 1.49f, 1.000277f, false)),
          m_substrate(props),
          m_specular(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))),
          m_cycles_approximation(read_cycles_approximation<N>(props)) {
        m_inv_eta2 = 1.f / (m_eta * m_eta);
        m_substrate.set_internal_reflectance(fresnel_diffuse_reflectance(1.f / m_eta));
        if (m_cycles_approximation) m_mean_t_out = 1.f - fresnel_diffuse_reflectance(m_eta);
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
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        float t_i = 1.f - fresnel_dielectric(cos_theta(wi), m_eta).R;
        float t_o = transmitted_out(cos_theta(wo));
        return m_substrate.base(ctx) * (m_inv_eta2 * t_i * t_o * kInvPi * cos_theta(wo));  // docs/bsdfs.md (23)
    }

    float pdf(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return 0.f;
        float t_i = 1.f - fresnel_dielectric(cos_theta(wi), m_eta).R;  // docs/bsdfs.md (24)
        return t_i * pdf_cosine_hemisphere(wo);
    }

    BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float u1, const Vec2f& u2) const override {
        BSDFSample<N> bs;
        if (cos_theta(wi) <= 0.f) return bs;
        float r_i = fresnel_dielectric(cos_theta(wi), m_eta).R;
        if (u1 < r_i) {  // docs/bsdfs.md (22), (24): value r_i * specular, probability r_i
            bs.wo = Vec3f(-wi.x(), -wi.y(), wi.z());
            bs.pdf = r_i;
            bs.lobe = kDeltaReflection;
            bs.weight = m_specular;
            return bs;
        }
        Vec3f wo = sample_cosine_hemisphere(u2);
        float pdf = (1.f - r_i) * pdf_cosine_hemisphere(wo);
        if (!(pdf > 0.f)) return bs;
        float t_o = transmitted_out(cos_theta(wo));
        bs.wo = wo;
        bs.pdf = pdf;
        bs.lobe = kDiffuseReflection;
        bs.weight = m_substrate.base(ctx) * (m_inv_eta2 * t_o);  // (23) / (24): t_i and cos/pi cancel
        return bs;
    }

    uint32_t flags() const override { return kDeltaReflection | kDiffuseReflection; }
    Spectrum<N> albedo(const BSDFContext& ctx) const override { return m_substrate.albedo(ctx); }

    /// ∂(f·|cos wo|)/∂c over the diffuse lobe, docs/bsdfs.md (35). Key 0 (diffuse_reflectance):
    /// (23) with ρ̃ replaced by ∂ρ̃/∂ρ from (34), which is a constant for nonlinear = false but
    /// 1/(1 − ρ Fdr)² for nonlinear = true, so there it depends on the current diffuse
    /// reflectance (the gradient at the present coefficients, not a global constant). Key 1
    /// (specular_reflectance): 0, the specular lobe is delta and not part of eval.
    Spectrum<N> eval_grad(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        if (key >= m_substrate.key_count() || cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        float t_i = 1.f - fresnel_dielectric(cos_theta(wi), m_eta).R;
        float t_o = transmitted_out(cos_theta(wo));
        return m_substrate.d_base(ctx, key) * (m_inv_eta2 * t_i * t_o * kInvPi * cos_theta(wo));
    }
    /// ∂(bs.weight)/∂c, docs/bsdfs.md (35): the delta sample's weight is specular_reflectance
    /// (22), so 1 for key 1 and 0 for key 0; the diffuse sample's closed-form weight ρ̃ (1 − R_o)/η²
    /// (24) gives ∂ρ̃/∂ρ (1 − R_o)/η² for key 0 (current-ρ dependent when nonlinear) and 0 for key 1.
    Spectrum<N> weight_grad(const BSDFContext& ctx, const Vec3f&, const BSDFSample<N>& bs, int key) const override {
        const bool specular_key = key == m_substrate.key_count();
        if (bs.lobe == kDeltaReflection) return Spectrum<N>::Constant(specular_key ? 1.f : 0.f);
        if (specular_key) return Spectrum<N>::Zero();
        float t_o = transmitted_out(cos_theta(bs.wo));
        return m_substrate.d_base(ctx, key) * (m_inv_eta2 * t_o);
    }

private:
    /// 1 − R(cos θo), the diffuse lobe's way out; its cosine-weighted mean 1 − Fdr(η) under
    /// cycles_approximation (docs/bsdfs.md (48)).
    float transmitted_out(float cos_o) const {
        return m_cycles_approximation ? m_mean_t_out : 1.f - fresnel_dielectric(cos_o, m_eta).R;
    }

    float m_eta, m_inv_eta2 = 1.f;
    PlasticSubstrate<N> m_substrate;  ///< ρ̃ after internal bounces, docs/bsdfs.md (23)
    Spectrum<N> m_specular;
    bool m_cycles_approximation;
    float m_mean_t_out = 0.f;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_plastic_bsdf(const Props& props) {
    return std::make_unique<SmoothPlastic<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_plastic_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_plastic_bsdf<16>(const Props&);

}  // namespace lpt
