// Isotropic microfacet distributions (Beckmann, GGX) for the rough plugins: D, Smith G1/G and
// microfacet-normal sampling with its pdf.
//   - GGX samples the distribution of visible normals (Heitz 2018, "Sampling the GGX
//     Distribution of Visible Normals"), pdf D_wi(m) = G1(wi,m) max(0, wi.m) D(m) / cos wi.
//   - Beckmann samples D(m) cos(theta_m) (Walter et al. 2007, classic), pdf D(m) cos(theta_m);
//     simpler than Beckmann VNDF and exact, at the price of more variance at grazing wi.
// Smith G1 is exact for both (Beckmann via erfc, not Walter's rational fit).
// Keys (read by read_distribution / read_alpha): distribution "beckmann"|"ggx" (default
// beckmann, as Mitsuba 3); alpha (float, default 0.1, > 0; roughness = RMS slope for Beckmann;
// values below 1e-4 are raised to 1e-4 as in Mitsuba 3); sample_visible (bool, read and
// ignored: GGX always samples visible normals, Beckmann never). Equations: docs/bsdfs.md (5)-(12).
// Roughness derivatives ∂D/∂α, ∂G1/∂α, ∂G/∂α (analytic, exact): docs/bsdfs.md (37)-(39).
#pragma once
#include "core/geometry.h"
#include "core/props.h"
#include <utility>

namespace lpt {

enum class MicrofacetType { Beckmann, GGX };

class MicrofacetDistribution {
public:
    /// Smallest roughness: smaller values (constructor or set_alpha) are raised to it.
    static constexpr float kMinAlpha = 1e-4f;

    MicrofacetDistribution(MicrofacetType type, float alpha);
    MicrofacetType type() const { return m_type; }
    float alpha() const { return m_alpha; }
    /// Replaces alpha, raised to kMinAlpha as in the constructor.
    /// Raised to kMinAlpha; throws std::invalid_argument if not finite.
    void set_alpha(float alpha);

    /// Normal distribution D(m), normalised so that ∫ D(m) cos(theta_m) dm = 1; 0 for m.z <= 0.
    /// docs/bsdfs.md (5), (6)
    float D(const Vec3f& m) const;
    /// Smith monostatic shadowing-masking; 0 when v sees the back of m (sign(v.m) != sign(v.z)).
    /// docs/bsdfs.md (7)
    float G1(const Vec3f& v, const Vec3f& m) const;
    /// Separable Smith G(wi, wo, m) = G1(wi, m) G1(wo, m).  docs/bsdfs.md (7)
    float G(const Vec3f& wi, const Vec3f& wo, const Vec3f& m) const { return G1(wi, m) * G1(wo, m); }

    /// {D(m), ∂D(m)/∂α} at the current α (the first bitwise equal to D(m)); ∂D/∂α is 0
    /// wherever D is identically 0.  docs/bsdfs.md (37)
    std::pair<float, float> D_dalpha(const Vec3f& m) const;
    float dD_dalpha(const Vec3f& m) const { return D_dalpha(m).second; }
    /// {G1(v, m), ∂G1(v, m)/∂α} (the first bitwise equal to G1(v, m); one erfc for Beckmann);
    /// ∂G1/∂α is 0 where G1 is identically 0 (back side) or 1 (tan θv = 0).  docs/bsdfs.md (38)
    std::pair<float, float> G1_dalpha(const Vec3f& v, const Vec3f& m) const;
    float dG1_dalpha(const Vec3f& v, const Vec3f& m) const { return G1_dalpha(v, m).second; }
    /// ∂G/∂α = ∂G1(wi) G1(wo) + G1(wi) ∂G1(wo).  docs/bsdfs.md (39)
    float dG_dalpha(const Vec3f& wi, const Vec3f& wo, const Vec3f& m) const {
        auto [gi, dgi] = G1_dalpha(wi, m);
        auto [go, dgo] = G1_dalpha(wo, m);
        return dgi * go + gi * dgo;
    }
    /// ∂(D(m) G(wi, wo, m))/∂α = ∂D G + D ∂G, the α-dependent factor of every rough
    /// plugin's eval, with each of D, G1(wi), G1(wo) evaluated once.  docs/bsdfs.md (39)
    float dDG_dalpha(const Vec3f& wi, const Vec3f& wo, const Vec3f& m) const {
        auto [d, dd] = D_dalpha(m);
        auto [gi, dgi] = G1_dalpha(wi, m);
        auto [go, dgo] = G1_dalpha(wo, m);
        return dd * (gi * go) + d * (dgi * go + gi * dgo);
    }

    /// Samples a microfacet normal (upper hemisphere) for wi in the upper hemisphere (callers
    /// flip wi to the +z side). docs/bsdfs.md (8), (9)
    Vec3f sample(const Vec3f& wi, const Vec2f& u) const;
    /// Density of sample() over m (solid angle).  docs/bsdfs.md (8), (9)
    float pdf(const Vec3f& wi, const Vec3f& m) const;
    /// f |cos wo| / pdf of a microfacet-sampled wo, without the Fresnel and colour factors:
    /// G1(wo, m) for GGX-VNDF, G |wi.m| / (|cos wi| cos theta_m) for Beckmann.
    /// Valid for reflection and refraction alike (the Jacobians cancel).  docs/bsdfs.md (12)
    float sample_weight(const Vec3f& wi, const Vec3f& wo, const Vec3f& m) const;

private:
    MicrofacetType m_type;
    float m_alpha;
};

/// "distribution" key; unknown names throw SceneError naming the field.
MicrofacetType read_distribution(const Props& props);
/// "alpha" key (default 0.1); <= 0 or anisotropic keys (alpha_u/alpha_v) throw SceneError.
float read_alpha(const Props& props);

/// Mirror reflection of w about m (both pointing away from the surface).
inline Vec3f reflect(const Vec3f& w, const Vec3f& m) { return 2.f * w.dot(m) * m - w; }
/// Refraction of w through the interface with normal m, given the signed transmitted cosine and
/// eta_ti from fresnel_dielectric(w.m, eta).  docs/bsdfs.md (2)
inline Vec3f refract(const Vec3f& w, const Vec3f& m, float cos_t, float eta_ti) {
    return m * (w.dot(m) * eta_ti + cos_t) - w * eta_ti;
}

}  // namespace lpt
