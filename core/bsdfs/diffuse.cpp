// "diffuse": ideal Lambertian reflector, one-sided (zero unless cos wi > 0 and cos wo > 0,
// as Mitsuba 3's diffuse). Sampling is cosine-weighted and independent of the reflectance.
// Keys: reflectance (rgb, default 0.5; signed values allowed for latent channels, never clamped;
// or a bitmap texture, core/texture.h). Equations: docs/bsdfs.md (13).
// A textured reflectance is looked up at ctx.uv for N = 3 only. Other N (latent channels) use
// the constant spectrum_from_rgb of the image's mean colour, which set_spectral overrides as
// for an untextured material: latent textures (grey image x scale + offset per channel) are
// issue 7, and eval_grad stays that of one coefficient per material.
#include "core/bsdf.h"
#include "core/texture.h"
#include "core/warp.h"
#include <optional>

namespace lpt {
namespace {

template <int N>
class Diffuse final : public BSDF<N> {
public:
    explicit Diffuse(const Props& props) {
        Texture tex = texture_from_props(props, "reflectance", Eigen::Array3f::Constant(0.5f));
        m_reflectance = spectrum_from_rgb<N>(tex.mean());  // the constant itself if untextured
        if constexpr (N == 3)
            if (!tex.is_constant()) m_texture = std::move(tex);
    }

    Spectrum<N> eval(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        return reflectance(ctx) * (kInvPi * cos_theta(wo));  // docs/bsdfs.md (13)
    }

    float pdf(const BSDFContext&, const Vec3f& wi, const Vec3f& wo) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return 0.f;
        return pdf_cosine_hemisphere(wo);
    }

    BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float, const Vec2f& u2) const override {
        BSDFSample<N> bs;
        if (cos_theta(wi) <= 0.f) return bs;
        bs.wo = sample_cosine_hemisphere(u2);
        bs.pdf = pdf_cosine_hemisphere(bs.wo);
        if (!(bs.pdf > 0.f)) return BSDFSample<N>();  // wo on the horizon: eval would be 0
        bs.lobe = kDiffuseReflection;
        bs.weight = reflectance(ctx);  // (R/pi cos) / (cos/pi), exactly
        return bs;
    }

    uint32_t flags() const override { return kDiffuseReflection; }
    Spectrum<N> albedo(const BSDFContext& ctx) const override { return reflectance(ctx); }

    Spectrum<N> eval_grad(const BSDFContext&, const Vec3f& wi, const Vec3f& wo, int) const override {
        if (cos_theta(wi) <= 0.f || cos_theta(wo) <= 0.f) return Spectrum<N>::Zero();
        return Spectrum<N>::Constant(kInvPi * cos_theta(wo));
    }

    std::vector<std::string> spectral_keys() const override { return {"reflectance"}; }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override {
        if (key != "reflectance") BSDF<N>::set_spectral(key, v);
        m_reflectance = v;
        m_texture.reset();  // a fitted coefficient replaces the image, for N = 3 too
    }

private:
    Spectrum<N> reflectance(const BSDFContext& ctx) const {
        if constexpr (N == 3)
            if (m_texture) return m_texture->eval(ctx.uv);
        return m_reflectance;
    }

    Spectrum<N> m_reflectance;
    std::optional<Texture> m_texture;  ///< only ever set for N = 3
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_diffuse_bsdf(const Props& props) {
    return std::make_unique<Diffuse<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_diffuse_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_diffuse_bsdf<16>(const Props&);

}  // namespace lpt
