// "diffuse": ideal Lambertian reflector, one-sided (zero unless cos wi > 0 and cos wo > 0,
// as Mitsuba 3's diffuse). Sampling is cosine-weighted and independent of the reflectance.
// Keys: reflectance (rgb, default 0.5; signed values allowed for latent channels, never clamped).
// Equations: docs/bsdfs.md (13).
#include "core/bsdf.h"
#include "core/warp.h"

namespace lpt {
namespace {

template <int N>
class Diffuse final : public BSDF<N> {
public:
    explicit Diffuse(const Props& props)
        : m_reflectance(spectrum_from_rgb<N>(props.get_rgb("reflectance", Eigen::Array3f::Constant(0.5f)))) {}

    Spectrum<N> eval(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        return m_reflectance * (kInvPi * cos_theta(wo));  // docs/bsdfs.md (13)
    }

    float pdf(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return 0.f;
        return pdf_cosine_hemisphere(wo);
    }

    BSDFSample<N> sample(const BSDFContext&, const Vec3f& wi, float, const Vec2f& u2) const override {
        BSDFSample<N> bs;
        if (cos_theta(wi) <= 0.f) return bs;
        bs.wo = sample_cosine_hemisphere(u2);
        bs.pdf = pdf_cosine_hemisphere(bs.wo);
        if (!(bs.pdf > 0.f)) return BSDFSample<N>();  // wo on the horizon: eval would be 0
        bs.lobe = kDiffuseReflection;
        bs.weight = m_reflectance;  // (R/pi cos) / (cos/pi), exactly
        return bs;
    }

    uint32_t flags() const override { return kDiffuseReflection; }
    Spectrum<N> albedo(const BSDFContext&) const override { return m_reflectance; }

    Spectrum<N> eval_grad(const BSDFContext&, const Vec3f& wi, const Vec3f& wo, int) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        return Spectrum<N>::Constant(kInvPi * cos_theta(wo));
    }

    std::vector<std::string> spectral_keys() const override { return {"reflectance"}; }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key != "reflectance") BSDF<N>::set_spectral(key, v);
        m_reflectance = v;
    }

private:
    Spectrum<N> m_reflectance;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_diffuse_bsdf(const Props& props) {
    return std::make_unique<Diffuse<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_diffuse_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_diffuse_bsdf<16>(const Props&);

}  // namespace lpt
