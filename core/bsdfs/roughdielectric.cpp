// "roughdielectric": rough interface between two dielectrics (Walter et al. 2007, "Microfacet
// Models for Refraction through Rough Surfaces"), Mitsuba 3's roughdielectric. Two-sided: wi
// below the surface is a path inside the interior. Reflection vs refraction is chosen with the
// Fresnel reflectance of the sampled microfacet (never the colours).
// Keys: distribution ("beckmann" | "ggx", default beckmann); alpha (float, default 0.1, > 0);
// int_ior (default 1.5046 = BK7), ext_ior (default 1.000277 = air), > 0 and distinct;
// specular_reflectance, specular_transmittance (rgb, default 1).
// Transmitted radiance is scaled by 1/eta^2 in TransportMode::Radiance only.
// Gradients w.r.t. the two colours (keys 0 and 1): docs/bsdfs.md (32)-(33); w.r.t. the scalar
// key "alpha" (roughness): docs/bsdfs.md (37)-(39), (41), (43).
// Equations: docs/bsdfs.md (1)-(2), (7)-(12), (18)-(21), (32)-(33), (37)-(39), (41), (43).
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/microfacet_bsdf.h"

namespace lpt {
namespace {

template <int N>
class RoughDielectric final : public MicrofacetBSDF<N> {
public:
    explicit RoughDielectric(const Props& props)
        : MicrofacetBSDF<N>(props),
          m_eta(read_relative_ior(props, 1.5046f, 1.000277f, true)),
          m_reflectance(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))),
          m_transmittance(spectrum_from_rgb<N>(props.get_rgb("specular_transmittance", Eigen::Array3f::Ones()))) {}

    Spectrum<N> eval(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const override {
        Half h;
        if (!half_vector(wi, wo, h)) return Spectrum<N>::Zero();
        float D = m_distr.D(h.m);
        if (D == 0.f) return Spectrum<N>::Zero();
        float F = fresnel(h);
        float G = m_distr.G(wi, wo, h.m);
        float cos_i = cos_theta(wi);
        if (h.reflect)  // docs/bsdfs.md (19)
            return m_reflectance * (F * D * G / (4.f * std::abs(cos_i)));
        float denom = h.wi_m + h.eta * h.wo_m;  // docs/bsdfs.md (20)
        float value = std::abs((1.f - F) * D * G * h.eta * h.eta * h.wi_m * h.wo_m / (cos_i * denom * denom));
        return m_transmittance * (value * radiance_scale(ctx, h.eta));
    }

    float pdf(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        Half h;
        if (!half_vector(wi, wo, h)) return 0.f;
        float F = fresnel(h);
        float p = m_distr.pdf(cos_theta(wi) > 0.f ? wi : Vec3f(-wi), h.m);  // docs/bsdfs.md (21)
        return std::abs(p * (h.reflect ? F : 1.f - F) * jacobian(h));
    }

    BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float u1, const Vec2f& u2) const override {
        BSDFSample<N> bs;
        float cos_i = cos_theta(wi);
        if (cos_i == 0.f) return bs;
        // Sample as seen from the side wi is on; m is then always in the upper hemisphere.
        Vec3f wi_up = cos_i > 0.f ? wi : Vec3f(-wi);
        Vec3f m = m_distr.sample(wi_up, u2);
        // Classic Beckmann sampling may pick a microfacet facing away from wi; no valid path.
        if (wi_up.dot(m) <= 0.f) return bs;
        float micro_pdf = m_distr.pdf(wi_up, m);
        FresnelDielectric f = fresnel_dielectric(wi.dot(m), m_eta);
        Half h;
        h.m = m;
        h.wi_m = wi.dot(m);
        bool reflect_lobe = u1 < f.R;
        Vec3f wo;
        if (reflect_lobe) {
            wo = reflect(wi, m);
            h.reflect = true;
            if (cos_theta(wo) * cos_i <= 0.f) return bs;
        } else {
            if (f.cos_t == 0.f) return bs;  // grazing refraction carries no energy
            wo = refract(wi, m, f.cos_t, f.eta_ti);
            h.reflect = false;
            h.eta = f.eta_it;
            if (cos_theta(wo) * cos_i >= 0.f) return bs;
        }
        h.wo_m = wo.dot(m);
        float pdf = std::abs(micro_pdf * (reflect_lobe ? f.R : 1.f - f.R) * jacobian(h));
        if (!(pdf > 0.f) || !std::isfinite(pdf)) return bs;
        float w = m_distr.sample_weight(wi_up, cos_i > 0.f ? wo : Vec3f(-wo), m);  // docs/bsdfs.md (12)
        bs.wo = wo;
        bs.pdf = pdf;
        if (reflect_lobe) {
            bs.lobe = kGlossyReflection;
            bs.weight = m_reflectance * w;
        } else {
            bs.lobe = kGlossyTransmission;
            bs.eta = f.eta_it;
            bs.weight = m_transmittance * (w * radiance_scale(ctx, f.eta_it));
        }
        return bs;
    }

    uint32_t flags() const override { return kGlossyReflection | kGlossyTransmission; }
    Spectrum<N> albedo(const BSDFContext&) const override { return m_transmittance; }

    /// ∂(f·|cos wo|)/∂colour, docs/bsdfs.md (32): key 0 (specular_reflectance) is (19) without
    /// the colour on reflection pairs and 0 on transmission pairs; key 1 (specular_transmittance)
    /// is (20) without the colour on transmission pairs and 0 on reflection pairs. Independent
    /// of both colours.
    Spectrum<N> eval_grad(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        Half h;
        if (!half_vector(wi, wo, h)) return Spectrum<N>::Zero();
        if (h.reflect != (key == 0)) return Spectrum<N>::Zero();  // the other colour's lobe
        float D = m_distr.D(h.m);
        if (D == 0.f) return Spectrum<N>::Zero();
        float F = fresnel(h);
        float G = m_distr.G(wi, wo, h.m);
        float cos_i = cos_theta(wi);
        if (h.reflect) return Spectrum<N>::Constant(F * D * G / (4.f * std::abs(cos_i)));
        float denom = h.wi_m + h.eta * h.wo_m;
        float value = std::abs((1.f - F) * D * G * h.eta * h.eta * h.wi_m * h.wo_m / (cos_i * denom * denom));
        return Spectrum<N>::Constant(value * radiance_scale(ctx, h.eta));
    }
    /// ∂(bs.weight)/∂colour, docs/bsdfs.md (33): sample() returns colour · w(12) (· s(18) for
    /// refraction) in closed form, so this is w (· s) for the sampled lobe's colour and 0 for the
    /// other, with m recovered as the generalised half vector of (wi, bs.wo) (bs.eta = η_it).
    Spectrum<N> weight_grad(const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<N>& bs, int key) const override {
        bool reflect_lobe = bs.lobe == kGlossyReflection;
        if (reflect_lobe != (key == 0)) return Spectrum<N>::Zero();
        Half h;
        half_vector(wi, bs.wo, h);  // h.m is set for any valid sample; the side checks do not matter here
        bool up = cos_theta(wi) > 0.f;
        float w = m_distr.sample_weight(up ? wi : Vec3f(-wi), up ? bs.wo : Vec3f(-bs.wo), h.m);
        return Spectrum<N>::Constant(reflect_lobe ? w : w * radiance_scale(ctx, bs.eta));
    }

    std::vector<std::string> spectral_keys() const override {
        return {"specular_reflectance", "specular_transmittance"};
    }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key == "specular_reflectance") m_reflectance = v;
        else if (key == "specular_transmittance") m_transmittance = v;
        else BSDF<N>::set_spectral(key, v);
    }

    /// ∂(f·|cos wo|)/∂α, docs/bsdfs.md (41): (19) and (20) with D G replaced by
    /// ∂(D G)/∂α = ∂D G + D ∂G from (37)-(39). D, G >= 0, so |(1 - F) D G X| = D G |(1 - F) X|
    /// and the absolute value passes to the α-free factor. F, η, the half vector and s (18) do
    /// not depend on α. weight_grad_scalar keeps the base-class default (∂eval/∂α)/pdf,
    /// docs/bsdfs.md (43): sample() returns colour·w(12)(·s), equal to eval/pdf, and path
    /// replay holds bs.wo and bs.pdf (including the Fresnel lobe probability) fixed.
    Spectrum<N> eval_grad_scalar(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        if (key != 0) throw std::invalid_argument("roughdielectric: scalar key index out of range");
        Half h;
        if (!half_vector(wi, wo, h)) return Spectrum<N>::Zero();
        if (m_distr.D(h.m) == 0.f) return Spectrum<N>::Zero();  // same zero cases as eval
        float dDG = m_distr.dDG_dalpha(wi, wo, h.m);
        float F = fresnel(h);
        float cos_i = cos_theta(wi);
        if (h.reflect) return m_reflectance * (F * dDG / (4.f * std::abs(cos_i)));
        float denom = h.wi_m + h.eta * h.wo_m;
        float factor = std::abs((1.f - F) * h.eta * h.eta * h.wi_m * h.wo_m / (cos_i * denom * denom));
        return m_transmittance * (dDG * factor * radiance_scale(ctx, h.eta));
    }

private:
    struct Half {
        Vec3f m = Vec3f::UnitZ();
        float wi_m = 0.f, wo_m = 0.f;
        float eta = 1.f;  ///< eta_t / eta_i from wi's side (transmission only)
        bool reflect = true;
    };

    // Generalised half vector (docs/bsdfs.md (10)-(11)), turned to the upper hemisphere; false
    // for configurations no microfacet can produce (backfacing microfacets, degenerate sums).
    bool half_vector(const Vec3f& wi, const Vec3f& wo, Half& h) const {
        float cos_i = cos_theta(wi), cos_o = cos_theta(wo);
        if (cos_i == 0.f || cos_o == 0.f) return false;
        h.reflect = cos_i * cos_o > 0.f;
        h.eta = h.reflect ? 1.f : (cos_i > 0.f ? m_eta : 1.f / m_eta);
        // Double precision: wi.m is a small difference of O(1) terms near grazing microfacets,
        // where 1 - F is steep; float rounding there breaks reciprocity by ~1%.
        Eigen::Vector3d i = wi.cast<double>(), o = wo.cast<double>();
        Eigen::Vector3d m = i + o * double(h.eta);
        double len = m.norm();
        if (!(len > 0.0)) return false;
        m /= len;
        if (m.z() < 0.0) m = -m;
        h.m = m.cast<float>();
        h.wi_m = float(i.dot(m));
        h.wo_m = float(o.dot(m));
        return h.wi_m * cos_i > 0.f && h.wo_m * cos_o > 0.f;
    }

    // F(wi.m) = F(wo.m) for a refraction pair, but from the denser side near the critical
    // angle cos_t^2 = 1 - (1 - cos^2) eta^2 cancels catastrophically (1% errors in 1 - F in
    // float); the side with the smaller |cosine| is well conditioned, and choosing it the same
    // way for (wi, wo) and (wo, wi) keeps eval reciprocal. sample() must use F(wi.m) (wo is
    // not known yet); the two agree to float precision except in that ill-conditioned corner.
    float fresnel(const Half& h) const {
        bool use_wo = !h.reflect && std::abs(h.wo_m) < std::abs(h.wi_m);
        return fresnel_dielectric(use_wo ? h.wo_m : h.wi_m, m_eta).R;
    }

    // dm/dwo: docs/bsdfs.md (10) for reflection, (11) for refraction.
    static float jacobian(const Half& h) {
        if (h.reflect) return 1.f / (4.f * h.wo_m);
        float denom = h.wi_m + h.eta * h.wo_m;
        return h.eta * h.eta * h.wo_m / (denom * denom);
    }

    static float radiance_scale(const BSDFContext& ctx, float eta) {  // docs/bsdfs.md (18)
        return ctx.mode == TransportMode::Radiance ? 1.f / (eta * eta) : 1.f;
    }

    using MicrofacetBSDF<N>::m_distr;  // nothing here caches alpha
    float m_eta;
    Spectrum<N> m_reflectance, m_transmittance;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_roughdielectric_bsdf(const Props& props) {
    return std::make_unique<RoughDielectric<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_roughdielectric_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_roughdielectric_bsdf<16>(const Props&);

}  // namespace lpt
