// "conductor": smooth metal, a perfect specular reflector weighted by conductor Fresnel.
// One-sided: no scattering unless cos wi > 0 (Mitsuba 3's conductor).
// Keys: specular_reflectance (rgb, default 1, multiplies F); eta, k (rgb, dimensionless complex
// IOR; Mitsuba 3 defaults eta = 0, k = 1 once either is given); material (string, only "none").
// With neither eta nor k, or material "none", it is a perfect mirror (F = 1), which is also
// Mitsuba 3's default. Named presets (Mitsuba's "Cu", "Au", ...) are rejected with a SceneError:
// they need a spectral IOR database that latentpt does not ship.
// Equations: docs/bsdfs.md (3), (14).
#include "core/bsdf.h"
#include "core/bsdfs/fresnel.h"

namespace lpt {
namespace {

template <int N>
class SmoothConductor final : public BSDF<N> {
public:
    explicit SmoothConductor(const Props& props)
        : m_specular(spectrum_from_rgb<N>(props.get_rgb("specular_reflectance", Eigen::Array3f::Ones()))),
          m_ior(read_conductor_ior<N>(props)) {}

    Spectrum<N> eval(const BSDFContext&, const Vec3f&, const Vec3f&) const override { return Spectrum<N>::Zero(); }
    float pdf(const BSDFContext&, const Vec3f&, const Vec3f&) const override { return 0.f; }

    BSDFSample<N> sample(const BSDFContext&, const Vec3f& wi, float, const Vec2f&) const override {
        BSDFSample<N> bs;
        if (cos_theta(wi) <= 0.f) return bs;
        bs.wo = Vec3f(-wi.x(), -wi.y(), wi.z());
        bs.pdf = 1.f;  // the only lobe
        bs.lobe = kDeltaReflection;
        bs.weight = m_specular * m_ior.fresnel(cos_theta(wi));  // docs/bsdfs.md (14)
        return bs;
    }

    uint32_t flags() const override { return kDeltaReflection; }
    Spectrum<N> albedo(const BSDFContext&) const override { return m_specular * m_ior.fresnel(1.f); }

    Spectrum<N> eval_grad(const BSDFContext&, const Vec3f&, const Vec3f&, int) const override {
        return Spectrum<N>::Zero();
    }
    Spectrum<N> weight_grad(const BSDFContext&, const Vec3f& wi, const BSDFSample<N>&, int) const override {
        return Spectrum<N>::Ones() * m_ior.fresnel(cos_theta(wi));  // d/dR of (14)
    }

    std::vector<std::string> spectral_keys() const override { return {"specular_reflectance"}; }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key != "specular_reflectance") BSDF<N>::set_spectral(key, v);
        m_specular = v;
    }

private:
    Spectrum<N> m_specular;
    ConductorIOR<N> m_ior;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_conductor_bsdf(const Props& props) {
    return std::make_unique<SmoothConductor<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_conductor_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_conductor_bsdf<16>(const Props&);

}  // namespace lpt
