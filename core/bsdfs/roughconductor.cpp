// "roughconductor": Cook-Torrance microfacet metal (Walter et al. 2007), one-sided (zero unless
// cos wi > 0 and cos wo > 0, as Mitsuba 3's roughconductor).
// Keys: distribution ("beckmann" | "ggx", default beckmann as Mitsuba 3); alpha (float, default
// 0.1, > 0, isotropic); specular_reflectance (rgb, default 1); eta, k, material as "conductor":
// neither eta nor k (or material "none") is a perfect F = 1 conductor. That is also what
// Mitsuba 3's code does (material defaults to "none" → eta 0, k 1), although Mitsuba's docs and
// Mitsuba 0.6 name copper as the default; copper needs an IOR database, which we do not ship.
// Gradients: ∂/∂specular_reflectance of eval and of the sample weight, docs/bsdfs.md (30)-(31);
// scalar key "alpha" (roughness), ∂/∂α of eval and of the weight, docs/bsdfs.md (37)-(40), (43).
// cycles_approximation (bool, validation only): F at the macro normal, core/bsdfs/cycles_approximation.h.
// Equations: docs/bsdfs.md (10), (12), (15)-(16), (30)-(31), (37)-(40), (43), (47).
#include "core/bsdfs/cycles_approximation.h"
#include "core/bsdfs/fresnel.h"
#include "core/bsdfs/microfacet_bsdf.h"

namespace lpt {
namespace {

template <int N>
class RoughConductor final : public MicrofacetBSDF<N> {
public:
    explicit RoughConductor(const Props& props)
        : MicrofacetBSDF<N>(props),
          m_specular(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))),
          m_ior(read_conductor_ior<N>(props)),
          m_cycles_approximation(read_cycles_approximation<N>(props)) {}

    Spectrum<N> eval(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float value = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_theta(wi));  // docs/bsdfs.md (15)
        if (value == 0.f) return Spectrum<N>::Zero();
        return m_specular * fresnel(wi, h) * value;
    }

    float pdf(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return 0.f;
        Vec3f h = (wi + wo).normalized();
        return m_distr.pdf(wi, h) / (4.f * wo.dot(h));  // docs/bsdfs.md (10), (16)
    }

    BSDFSample<N> sample(const BSDFContext&, const Vec3f& wi, float, const Vec2f& u2) const override {
        BSDFSample<N> bs;
        if (cos_theta(wi) <= 0.f) return bs;
        Vec3f m = m_distr.sample(wi, u2);
        Vec3f wo = reflect(wi, m);
        float wo_m = wo.dot(m);
        if (cos_theta(wo) <= 0.f || wo_m <= 0.f) return bs;
        float pdf = m_distr.pdf(wi, m) / (4.f * wo_m);
        if (!(pdf > 0.f) || !std::isfinite(pdf)) return bs;
        bs.wo = wo;
        bs.pdf = pdf;
        bs.lobe = kGlossyReflection;
        bs.weight = m_specular * fresnel(wi, m) * m_distr.sample_weight(wi, wo, m);  // (12)
        return bs;
    }

    uint32_t flags() const override { return kGlossyReflection; }
    Spectrum<N> albedo(const BSDFContext&) const override { return m_specular * m_ior.fresnel(1.f); }

    /// ∂(f·|cos wo|)/∂specular_reflectance = F(wi·h) D G / (4 cos θi), docs/bsdfs.md (30): eval
    /// with the colour replaced by ones (same zero cases), independent of the colour.
    Spectrum<N> eval_grad(const BSDFContext&, const Vec3f& wi, const Vec3f& wo, int) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float value = m_distr.D(h) * m_distr.G(wi, wo, h) / (4.f * cos_theta(wi));
        if (value == 0.f) return Spectrum<N>::Zero();
        return fresnel(wi, h) * value;
    }
    /// ∂(bs.weight)/∂specular_reflectance = F(wi·m) w(12), docs/bsdfs.md (31): the derivative of
    /// the closed form sample() uses (equal to eval_grad/pdf only up to rounding), with the
    /// microfacet normal m recovered as the reflection half vector of (wi, bs.wo).
    Spectrum<N> weight_grad(const BSDFContext&, const Vec3f& wi, const BSDFSample<N>& bs, int) const override {
        Vec3f m = (wi + bs.wo).normalized();
        return fresnel(wi, m) * m_distr.sample_weight(wi, bs.wo, m);
    }

    std::vector<std::string> spectral_keys() const override { return {"specular_reflectance"}; }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key != "specular_reflectance") BSDF<N>::set_spectral(key, v);
        m_specular = v;
    }

    /// ∂(f·|cos wo|)/∂α = specular_reflectance · F(wi·h) (∂D G + D ∂G) / (4 cos θi),
    /// docs/bsdfs.md (40): (15) by the product rule with (37)-(39); same zero cases as eval.
    /// weight_grad_scalar keeps the base-class default (∂eval/∂α)/pdf, docs/bsdfs.md (43):
    /// sample() returns the closed form colour·F·w(12), which equals eval/pdf, but w's own
    /// α-derivative also contains -eval·(∂pdf/∂α)/pdf² (the sampling density moves with α);
    /// path replay holds bs.wo and bs.pdf fixed, so only the numerator is differentiated.
    Spectrum<N> eval_grad_scalar(const BSDFContext&, const Vec3f& wi, const Vec3f& wo, int key) const override {
        if (key != 0) throw std::invalid_argument("roughconductor: scalar key index out of range");
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        Vec3f h = (wi + wo).normalized();
        float dvalue = m_distr.dDG_dalpha(wi, wo, h) / (4.f * cos_theta(wi));
        if (dvalue == 0.f) return Spectrum<N>::Zero();
        return m_specular * fresnel(wi, h) * dvalue;
    }

private:
    /// F at the microfacet normal m; at the macro normal under cycles_approximation
    /// (docs/bsdfs.md (47)).
    Spectrum<N> fresnel(const Vec3f& wi, const Vec3f& m) const {
        return m_ior.fresnel(m_cycles_approximation ? cos_theta(wi) : wi.dot(m));
    }

    using MicrofacetBSDF<N>::m_distr;  // nothing here caches alpha
    Spectrum<N> m_specular;
    ConductorIOR<N> m_ior;
    bool m_cycles_approximation;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_roughconductor_bsdf(const Props& props) {
    return std::make_unique<RoughConductor<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_roughconductor_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_roughconductor_bsdf<16>(const Props&);

}  // namespace lpt
