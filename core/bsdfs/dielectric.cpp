// "dielectric": smooth interface between two dielectrics (glass, water): delta reflection and
// delta refraction, chosen with probability R and 1 - R (Fresnel only, never the colours).
// Two-sided by nature: wi below the surface means the path is inside the interior medium.
// Keys: int_ior (float or IOR name, default 1.5046 = BK7), ext_ior (default 1.000277 = air),
// both > 0; specular_reflectance, specular_transmittance (rgb, default 1; physically 1).
// Transmitted radiance is scaled by 1/eta^2 in TransportMode::Radiance only.
// Equations: docs/bsdfs.md (1)-(2), (17)-(18).
#include "core/bsdf.h"
#include "core/bsdfs/fresnel.h"

namespace lpt {
namespace {

template <int N>
class SmoothDielectric final : public BSDF<N> {
public:
    explicit SmoothDielectric(const Props& props)
        : m_eta(read_relative_ior(props, 1.5046f, 1.000277f, false)),
          m_reflectance(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))),
          m_transmittance(spectrum_from_rgb<N>(props.get_rgb("specular_transmittance", Eigen::Array3f::Ones()))) {}

    Spectrum<N> eval(const BSDFContext&, const Vec3f&, const Vec3f&) const override { return Spectrum<N>::Zero(); }
    float pdf(const BSDFContext&, const Vec3f&, const Vec3f&) const override { return 0.f; }

    BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float u1, const Vec2f&) const override {
        BSDFSample<N> bs;
        float cos_i = cos_theta(wi);
        if (cos_i == 0.f) return bs;
        FresnelDielectric f = fresnel_dielectric(cos_i, m_eta);
        if (u1 < f.R) {  // docs/bsdfs.md (17): reflect with probability R, value R → weight 1
            bs.wo = Vec3f(-wi.x(), -wi.y(), wi.z());
            bs.pdf = f.R;
            bs.lobe = kDeltaReflection;
            bs.weight = m_reflectance;
            return bs;
        }
        bs.wo = Vec3f(-f.eta_ti * wi.x(), -f.eta_ti * wi.y(), f.cos_t);  // docs/bsdfs.md (2)
        bs.pdf = 1.f - f.R;
        bs.lobe = kDeltaTransmission;
        bs.eta = f.eta_it;
        // docs/bsdfs.md (18): radiance is compressed by (eta_i/eta_t)^2 entering a denser medium.
        float scale = ctx.mode == TransportMode::Radiance ? f.eta_ti * f.eta_ti : 1.f;
        bs.weight = m_transmittance * scale;
        return bs;
    }

    uint32_t flags() const override { return kDeltaReflection | kDeltaTransmission; }
    Spectrum<N> albedo(const BSDFContext&) const override { return m_transmittance; }

    Spectrum<N> eval_grad(const BSDFContext&, const Vec3f&, const Vec3f&, int) const override {
        return Spectrum<N>::Zero();
    }
    Spectrum<N> weight_grad(const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<N>& bs, int key) const override {
        if (bs.lobe == kDeltaReflection) return Spectrum<N>::Constant(key == 0 ? 1.f : 0.f);  // d/dR of (17)
        if (key == 0) return Spectrum<N>::Zero();
        float eta_ti = fresnel_dielectric(cos_theta(wi), m_eta).eta_ti;  // d/dT of (18)
        return Spectrum<N>::Constant(ctx.mode == TransportMode::Radiance ? eta_ti * eta_ti : 1.f);
    }

    std::vector<std::string> spectral_keys() const override {
        return {"specular_reflectance", "specular_transmittance"};
    }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key == "specular_reflectance") m_reflectance = v;
        else if (key == "specular_transmittance") m_transmittance = v;
        else BSDF<N>::set_spectral(key, v);
    }

private:
    float m_eta;
    Spectrum<N> m_reflectance, m_transmittance;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_dielectric_bsdf(const Props& props) {
    return std::make_unique<SmoothDielectric<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_dielectric_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_dielectric_bsdf<16>(const Props&);

}  // namespace lpt
