// BSDF interface, templated on the channel count N (3: RGB, 16: latent). All directions are in
// the local shading frame (normal = +z) and point away from the surface: wi toward where the
// path came from, wo the scattered direction. Values are signed-safe: nothing here may assume
// reflectance >= 0 (latent reflectances cross zero), and sampling depends only on geometry and
// roughness, never on the sign or size of the spectral coefficients. Equations: docs/bsdfs.md.
#pragma once
#include "core/geometry.h"
#include "core/props.h"
#include "core/spectrum.h"
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace lpt {

enum BSDFFlags : uint32_t {
    kNoLobe = 0,
    kDiffuseReflection = 1u << 0,
    kGlossyReflection = 1u << 1,
    kDeltaReflection = 1u << 2,
    kGlossyTransmission = 1u << 3,
    kDeltaTransmission = 1u << 4,
    kDelta = kDeltaReflection | kDeltaTransmission,
    kTransmission = kGlossyTransmission | kDeltaTransmission,
    kNonDelta = kDiffuseReflection | kGlossyReflection | kGlossyTransmission,
};

/// Radiance: camera paths (the only mode the renderer uses); Importance: light paths, where
/// refraction does not rescale by 1/eta^2 (Veach's non-symmetric BSDF adjoint).
enum class TransportMode { Radiance, Importance };

struct BSDFContext {
    TransportMode mode = TransportMode::Radiance;
    Vec2f uv = Vec2f::Zero();  ///< surface uv, for textured parameters
};

template <int N>
struct BSDFSample {
    Vec3f wo = Vec3f::Zero();
    /// Solid-angle pdf of wo for non-delta lobes; for a delta lobe, the discrete probability of
    /// having chosen that lobe. 0 marks a failed sample.
    float pdf = 0.f;
    float eta = 1.f;                           ///< relative IOR across the interface for a transmission, else 1
    uint32_t lobe = kNoLobe;                   ///< the single BSDFFlags bit of the sampled lobe
    Spectrum<N> weight = Spectrum<N>::Zero();  ///< f * |cos wo| / pdf (delta: the lobe's value / pdf)
    bool valid() const { return pdf > 0.f; }
};

/// Whether a BSDF is the Lambertian reflector ("diffuse"), alone or inside "twosided". The
/// tracer samples those from directions it warps for the whole shade queue at once
/// (sample_cosine_hemisphere_batch) through lambertian_sample below, which is also
/// Diffuse::sample itself, so the two cannot drift apart.
enum class Lambertian : uint8_t { No, OneSided, TwoSided };

/// Lambertian BSDF sample from a cosine-warped direction `wo` of the upper hemisphere: one-sided
/// needs cos wi > 0; two-sided mirrors a lower-side wi and the result (as TwoSided does).
/// Weight = reflectance exactly, (R/pi cos) / (cos/pi) (docs/bsdfs.md (13)).
template <int N>
BSDFSample<N> lambertian_sample(Lambertian sides, const Vec3f& wi, const Vec3f& wo, const Spectrum<N>& reflectance) {
    const bool below = sides == Lambertian::TwoSided && cos_theta(wi) < 0.f;
    BSDFSample<N> bs;
    if ((below ? -cos_theta(wi) : cos_theta(wi)) <= 0.f || !(cos_theta(wo) > 0.f))
        return bs;  // wo on the horizon: eval = 0
    bs.wo = below ? Vec3f(wo.x(), wo.y(), -wo.z()) : wo;
    bs.pdf = cos_theta(wo) * kInvPi;
    bs.lobe = kDiffuseReflection;
    bs.weight = reflectance;
    return bs;
}

template <int N>
class BSDF {
public:
    virtual ~BSDF() = default;
    /// f(wi, wo) * |cos wo| over the non-delta lobes (delta lobes evaluate to zero).
    virtual Spectrum<N> eval(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const = 0;
    /// Solid-angle density with which sample() produces wo, over the non-delta lobes.
    virtual float pdf(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo) const = 0;
    /// u1 picks a lobe, u2 the direction.
    virtual BSDFSample<N> sample(const BSDFContext& ctx, const Vec3f& wi, float u1, const Vec2f& u2) const = 0;
    /// OR of the lobes this BSDF can produce.
    virtual uint32_t flags() const = 0;
    /// Hemispherical reflectance-like colour for the albedo AOV only (not an integral; a display
    /// value): no estimator may use it.
    virtual Spectrum<N> albedo(const BSDFContext& ctx) const = 0;
    /// Whether light arriving below the shading normal (cos wi < 0) is scattered at all. Mitsuba's
    /// reflecting BSDFs are black from behind unless wrapped in twosided; transmissive ones see
    /// both sides. The latent renderer needs it where no BSDF value is at hand (Ĩa, Ĩc).
    virtual bool scatters_from_below() const { return (flags() & kTransmission) != 0; }
    /// Lambertian::No unless sample() is lambertian_sample() of a cosine-warped direction.
    virtual Lambertian lambertian() const { return Lambertian::No; }
    /// The reflectance ρ that lambertian_sample weights with, where lambertian() != No (the
    /// tracer samples those vertices from its batch-warped directions); zero elsewhere.
    virtual Spectrum<N> lambertian_reflectance(const BSDFContext&) const { return Spectrum<N>::Zero(); }

    /// Spectral coefficients exposed to fitting, by scene-file key (e.g. "reflectance"); the
    /// latent renderer fills them from its ParamStore (docs/params.md).
    virtual std::vector<std::string> spectral_keys() const { return {}; }
    /// Replaces one of spectral_keys(); throws std::invalid_argument for any other key.
    virtual void set_spectral(const std::string& key, const Spectrum<N>& value) {
        throw std::invalid_argument("BSDF has no spectral coefficient '" + key + "'");
    }

    /// ∂(f·|cos wo|)/∂c for the coefficient c = spectral_keys()[key], per channel, over the
    /// non-delta lobes. f is affine in each coefficient except the diffuse colour of plastics
    /// with nonlinear = true (then this depends on c); no division by f anywhere
    /// (docs/path-replay.md). The base class throws std::logic_error.
    virtual Spectrum<N> eval_grad(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const {
        throw std::logic_error("this BSDF type has no coefficient gradients yet");
    }
    /// ∂(bs.weight)/∂c for a sample this BSDF returned. Default: non-delta lobes, whose weight is
    /// eval/pdf with a pdf that ignores the coefficients. BSDFs with delta lobes override it.
    virtual Spectrum<N> weight_grad(const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<N>& bs, int key) const {
        return eval_grad(ctx, wi, bs.wo, key) / bs.pdf;
    }

    /// Scalar parameters exposed to fitting (rough BSDFs: {"alpha"}). Sampling depends on them,
    /// but path replay treats sampled directions and pdfs as constants (docs/path-replay.md).
    virtual std::vector<std::string> scalar_keys() const { return {}; }
    virtual float get_scalar(const std::string& key) const {
        throw std::invalid_argument("BSDF has no scalar parameter '" + key + "'");
    }
    virtual void set_scalar(const std::string& key, float value) {
        throw std::invalid_argument("BSDF has no scalar parameter '" + key + "'");
    }
    /// ∂(f·|cos wo|)/∂s for s = scalar_keys()[key], per channel, non-delta lobes.
    virtual Spectrum<N> eval_grad_scalar(const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, int key) const {
        throw std::logic_error("this BSDF type has no scalar-parameter gradients");
    }
    /// ∂(bs.weight)/∂s with the sampled direction and its pdf held fixed: (∂f/∂s)/pdf by default.
    virtual Spectrum<N> weight_grad_scalar(const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<N>& bs,
                                           int key) const {
        return eval_grad_scalar(ctx, wi, bs.wo, key) / bs.pdf;
    }

    bool has_delta() const { return (flags() & kDelta) != 0; }
    bool is_delta() const { return (flags() & kNonDelta) == 0; }
};

/// Builds a BSDF from its description (explicit type table in core/bsdfs/registry.cpp).
/// Unknown types and bad values throw SceneError naming props.file and the field.
template <int N>
std::unique_ptr<BSDF<N>> make_bsdf(const Props& props);

/// A scene file's BSDF description, checked as the loaders need it: built once as an RGB BSDF
/// (each BSDF validates its values), every property read by its constructor (a misspelt key is
/// an error, not a silent default) and no negative colour. Throws SceneError naming the field.
void check_bsdf_description(const Props& props);

}  // namespace lpt
