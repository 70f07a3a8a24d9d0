// "diffuse": ideal Lambertian reflector, one-sided (zero unless cos wi > 0 and cos wo > 0,
// as Mitsuba 3's diffuse). Sampling is cosine-weighted and independent of the reflectance.
// Keys: reflectance (rgb, default 0.5; signed values allowed for latent channels, never clamped;
// or a bitmap texture, core/texture.h). Equations: docs/bsdfs.md (13).
// A textured reflectance is the texel's RGB for N = 3 and g(uv)·s + o for latent channels
// (core/surface_colour.h), fitted as reflectance.scale and reflectance.offset.
#include "core/bsdf.h"
#include "core/surface_colour.h"
#include "core/warp.h"

namespace lpt {
namespace {

template <int N>
class Diffuse final : public BSDF<N> {
public:
    explicit Diffuse(const Props& props) : m_reflectance(props, "reflectance", Eigen::Array3f::Constant(0.5f)) {}

    Spectrum<N> eval(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        return m_reflectance.eval(ctx) * (kInvPi * cos_theta(wo));  // docs/bsdfs.md (13)
    }

    float pdf(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return 0.f;
        return pdf_cosine_hemisphere(wo);
    }

    BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float, const Vec2f& u2) const override {
        if (cos_theta(wi) <= 0.f) return BSDFSample<N>();
        return lambertian_sample<N>(Lambertian::OneSided, wi, sample_cosine_hemisphere(u2), m_reflectance.eval(ctx));
    }

    uint32_t flags() const override { return kDiffuseReflection; }
    Lambertian lambertian() const override { return Lambertian::OneSided; }
    Spectrum<N> lambertian_reflectance(const BSDFContext& ctx) const override { return m_reflectance.eval(ctx); }
    Spectrum<N> albedo(const BSDFContext& ctx) const override { return m_reflectance.eval(ctx); }

    /// ∂ρ/∂c · cos/π: 1 for the constant, g(uv) for .scale, 1 for .offset.
    Spectrum<N> eval_grad(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        return Spectrum<N>::Constant(m_reflectance.factor(ctx, key) * kInvPi * cos_theta(wo));
    }

    std::vector<std::string> spectral_keys() const override { return m_reflectance.keys(); }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        // A fitted constant replaces an RGB image (N = 3); latent textures keep theirs.
        if (!m_reflectance.set(key, v)) BSDF<N>::set_spectral(key, v);
    }

private:
    SurfaceColour<N> m_reflectance;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_diffuse_bsdf(const Props& props) {
    return std::make_unique<Diffuse<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_diffuse_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_diffuse_bsdf<16>(const Props&);

}  // namespace lpt
