// "twosided": makes a one-sided reflection BSDF scatter on both faces, as Mitsuba 3's twosided
// with a single nested BSDF: when wi is below the surface, wi and wo are mirrored through the
// tangent plane (z negated) so the nested BSDF sees its front side, and results mirrored back.
// Keys: bsdf (nested object, required; a reflection-only BSDF — transmissive BSDFs are
// two-sided already and are rejected, as in Mitsuba 3).
// Scalar parameters (roughness) are the nested BSDF's, forwarded with the same mirroring.
// Equations: docs/bsdfs.md (29), (43).
#include "core/bsdf.h"

namespace lpt {
namespace {

inline Vec3f flip_z(const Vec3f& w) { return Vec3f(w.x(), w.y(), -w.z()); }

template <int N>
class TwoSided final : public BSDF<N> {
public:
    explicit TwoSided(const Props& props) {
        auto child = props.get_child("bsdf");
        if (!child) props.fail("bsdf", "twosided needs a nested BSDF under the key 'bsdf'");
        m_nested = make_bsdf<N>(*child);
        if (m_nested->flags() & kTransmission)
            props.fail("bsdf", "twosided can only wrap reflection BSDFs, not '" + child->type +
                                   "' (transmissive BSDFs are already two-sided)");
    }

    Spectrum<N> eval(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const override {
        return cos_theta(wi) < 0.f ? m_nested->eval(ctx, flip_z(wi), flip_z(wo)) : m_nested->eval(ctx, wi, wo);
    }

    float pdf(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const override {
        return cos_theta(wi) < 0.f ? m_nested->pdf(ctx, flip_z(wi), flip_z(wo)) : m_nested->pdf(ctx, wi, wo);
    }

    BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float u1, const Vec2f& u2) const override {
        if (cos_theta(wi) >= 0.f) return m_nested->sample(ctx, wi, u1, u2);
        BSDFSample<N> bs = m_nested->sample(ctx, flip_z(wi), u1, u2);
        bs.wo = flip_z(bs.wo);
        return bs;
    }

    uint32_t flags() const override { return m_nested->flags(); }
    bool scatters_from_below() const override { return true; }
    Lambertian lambertian() const override {
        return m_nested->lambertian() == Lambertian::OneSided ? Lambertian::TwoSided : Lambertian::No;
    }
    Spectrum<N> albedo(const BSDFContext& ctx) const override { return m_nested->albedo(ctx); }
    Spectrum<N> lambertian_reflectance(const BSDFContext& ctx) const override {
        return m_nested->lambertian_reflectance(ctx);
    }

    Spectrum<N> eval_grad(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        return cos_theta(wi) < 0.f ? m_nested->eval_grad(ctx, flip_z(wi), flip_z(wo), key)
                                   : m_nested->eval_grad(ctx, wi, wo, key);
    }
    Spectrum<N> weight_grad(const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<N>& bs, int key) const override {
        if (cos_theta(wi) >= 0.f) return m_nested->weight_grad(ctx, wi, bs, key);
        BSDFSample<N> flipped = bs;
        flipped.wo = flip_z(bs.wo);
        return m_nested->weight_grad(ctx, flip_z(wi), flipped, key);
    }
    std::vector<std::string> spectral_keys() const override { return m_nested->spectral_keys(); }
    void set_spectral(const std::string& key, const Spectrum<N>& v) override { m_nested->set_spectral(key, v); }

    std::vector<std::string> scalar_keys() const override { return m_nested->scalar_keys(); }
    float get_scalar(const std::string& key) const override { return m_nested->get_scalar(key); }
    void set_scalar(const std::string& key, float value) override { m_nested->set_scalar(key, value); }
    Spectrum<N> eval_grad_scalar(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const override {
        return cos_theta(wi) < 0.f ? m_nested->eval_grad_scalar(ctx, flip_z(wi), flip_z(wo), key)
                                   : m_nested->eval_grad_scalar(ctx, wi, wo, key);
    }
    Spectrum<N> weight_grad_scalar(const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<N>& bs,
                                   int key) const override {
        if (cos_theta(wi) >= 0.f) return m_nested->weight_grad_scalar(ctx, wi, bs, key);
        BSDFSample<N> flipped = bs;
        flipped.wo = flip_z(bs.wo);
        return m_nested->weight_grad_scalar(ctx, flip_z(wi), flipped, key);
    }

private:
    std::unique_ptr<BSDF<N>> m_nested;
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_twosided_bsdf(const Props& props) {
    return std::make_unique<TwoSided<N>>(props);
}
template std::unique_ptr<BSDF<3>> make_twosided_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_twosided_bsdf<16>(const Props&);

}  // namespace lpt
