// Beckmann and GGX microfacet distributions. Equations: docs/bsdfs.md (5)-(12); roughness
// derivatives (37)-(39).
#include "core/bsdfs/microfacet.h"
#include <stdexcept>
#include <algorithm>
#include <cmath>
#include <string>

namespace lpt {

MicrofacetDistribution::MicrofacetDistribution(MicrofacetType type, float alpha)
    : m_type(type), m_alpha(std::max(alpha, kMinAlpha)) {}

void MicrofacetDistribution::set_alpha(float alpha) {
    // A fit step must never leave a NaN roughness behind: every rough plugin relies on this.
    if (!std::isfinite(alpha)) throw std::invalid_argument("microfacet roughness alpha must be finite");
    m_alpha = std::max(alpha, kMinAlpha);
}

float MicrofacetDistribution::D(const Vec3f& m) const {
    float c2 = m.z() * m.z();
    if (m.z() <= 0.f) return 0.f;
    // tan^2 from the tangential components, not 1/c2 - 1: no cancellation for sharp lobes.
    float t2 = (m.x() * m.x() + m.y() * m.y()) / c2;
    float a2 = m_alpha * m_alpha;
    if (m_type == MicrofacetType::Beckmann)  // docs/bsdfs.md (5)
        return std::exp(-t2 / a2) / (kPi * a2 * c2 * c2);
    float b = 1.f + t2 / a2;  // docs/bsdfs.md (6)
    return 1.f / (kPi * a2 * c2 * c2 * b * b);
}

float MicrofacetDistribution::G1(const Vec3f& v, const Vec3f& m) const {
    if (v.dot(m) * v.z() <= 0.f) return 0.f;
    float xy2 = v.x() * v.x() + v.y() * v.y();
    if (xy2 == 0.f) return 1.f;
    float at2 = m_alpha * m_alpha * xy2 / (v.z() * v.z());                         // (alpha tan theta_v)^2
    if (m_type == MicrofacetType::GGX) return 2.f / (1.f + std::sqrt(1.f + at2));  // docs/bsdfs.md (7)
    // Beckmann Lambda(a), a = 1 / (alpha tan theta); erfc keeps precision for large a.
    double a = 1.0 / std::sqrt(double(at2));
    double lambda = 0.5 * (std::exp(-a * a) / (a * std::sqrt(double(kPi))) - std::erfc(a));
    return float(1.0 / (1.0 + std::max(0.0, lambda)));
}

std::pair<float, float> MicrofacetDistribution::D_dalpha(const Vec3f& m) const {
    if (m.z() <= 0.f) return {0.f, 0.f};
    // D exactly as D(); the derivative is D times the closed-form d ln D / dα, (37).
    float c2 = m.z() * m.z();
    float t2 = (m.x() * m.x() + m.y() * m.y()) / c2;
    float a2 = m_alpha * m_alpha;
    // D == 0 (far tail, or tan²θm overflowing for m.z ~ 0): the derivative's limit is 0; the
    // guard keeps 0 · inf out.
    if (m_type == MicrofacetType::Beckmann) {  // d ln D/dα = 2 (tan²θm − α²) / α³
        float D = std::exp(-t2 / a2) / (kPi * a2 * c2 * c2);
        if (D == 0.f) return {D, 0.f};
        return {D, D * (2.f * (t2 - a2) / (a2 * m_alpha))};
    }
    float b = 1.f + t2 / a2;  // GGX: d ln D/dα = 2 (tan²θm − α²) / (α (α² + tan²θm))
    float D = 1.f / (kPi * a2 * c2 * c2 * b * b);
    if (D == 0.f) return {D, 0.f};
    return {D, D * (2.f * (t2 - a2) / (m_alpha * (a2 + t2)))};
}

std::pair<float, float> MicrofacetDistribution::G1_dalpha(const Vec3f& v, const Vec3f& m) const {
    // Same cases and value as G1(); docs/bsdfs.md (7), (38).
    if (v.dot(m) * v.z() <= 0.f) return {0.f, 0.f};
    float xy2 = v.x() * v.x() + v.y() * v.y();
    if (xy2 == 0.f) return {1.f, 0.f};
    float at2 = m_alpha * m_alpha * xy2 / (v.z() * v.z());  // (alpha tan theta_v)^2
    // v.z ~ 0 overflows α² tan²θv: G1 evaluates to exactly 0 there and ∂G1/∂α → 0 (both
    // formulas below would give 0 · inf).
    if (std::isinf(at2)) return {0.f, 0.f};
    if (m_type == MicrofacetType::GGX) {
        // G1 = 2 / (1 + s), s = sqrt(1 + α² tan²θv): ∂G1/∂α = −2 α tan²θv / (s (1 + s)²),
        // as −2 (at2 / s) / (α (1 + s)²) so that no intermediate overflows.
        float s = std::sqrt(1.f + at2);
        return {2.f / (1.f + s), -2.f * (at2 / s) / (m_alpha * (1.f + s) * (1.f + s))};
    }
    // Beckmann, in double as G1: with a = 1/(α tan θv), dΛ/da = −exp(−a²) / (2 a² √π) (the
    // erfc term's derivative, −2/√π exp(−a²), cancels most of the first term's), da/dα = −a/α,
    // so dΛ/dα = exp(−a²) / (2 a α √π) and ∂G1/∂α = −G1² dΛ/dα.
    double a = 1.0 / std::sqrt(double(at2));
    double e = std::exp(-a * a), sqrt_pi = std::sqrt(double(kPi));
    double lambda = 0.5 * (e / (a * sqrt_pi) - std::erfc(a));
    double g1 = 1.0 / (1.0 + std::max(0.0, lambda));
    return {float(g1), float(-g1 * g1 * e / (2.0 * a * double(m_alpha) * sqrt_pi))};
}

Vec3f MicrofacetDistribution::sample(const Vec3f& wi, const Vec2f& u) const {
    if (m_type == MicrofacetType::Beckmann) {  // docs/bsdfs.md (9)
        float t2 = -m_alpha * m_alpha * std::log1p(-std::min(u.x(), 1.f - 1e-7f));
        float cos_m = 1.f / std::sqrt(1.f + t2);
        float sin_m = std::sqrt(std::max(0.f, 1.f - cos_m * cos_m));
        float phi = 2.f * kPi * u.y();
        return Vec3f(sin_m * std::cos(phi), sin_m * std::sin(phi), cos_m);
    }
    // GGX visible normals, Heitz 2018: stretch wi to the alpha = 1 configuration, sample the
    // projected hemisphere there, unstretch.  docs/bsdfs.md (8)
    Vec3f vh = Vec3f(m_alpha * wi.x(), m_alpha * wi.y(), wi.z()).normalized();
    float len2 = vh.x() * vh.x() + vh.y() * vh.y();
    Vec3f t1 = len2 > 0.f ? Vec3f(-vh.y(), vh.x(), 0.f) / std::sqrt(len2) : Vec3f(1.f, 0.f, 0.f);
    Vec3f t2 = vh.cross(t1);
    float r = std::sqrt(u.x()), phi = 2.f * kPi * u.y();
    float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
    float s = 0.5f * (1.f + vh.z());
    p2 = (1.f - s) * std::sqrt(std::max(0.f, 1.f - p1 * p1)) + s * p2;
    Vec3f nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.f, 1.f - p1 * p1 - p2 * p2)) * vh;
    return Vec3f(m_alpha * nh.x(), m_alpha * nh.y(), std::max(1e-7f, nh.z())).normalized();
}

float MicrofacetDistribution::pdf(const Vec3f& wi, const Vec3f& m) const {
    if (m_type == MicrofacetType::Beckmann) return D(m) * std::max(0.f, m.z());  // docs/bsdfs.md (9)
    if (wi.z() <= 0.f) return 0.f;
    return D(m) * G1(wi, m) * std::max(0.f, wi.dot(m)) / wi.z();  // docs/bsdfs.md (8)
}

float MicrofacetDistribution::sample_weight(const Vec3f& wi, const Vec3f& wo, const Vec3f& m) const {
    if (m_type == MicrofacetType::GGX) return G1(wo, m);  // docs/bsdfs.md (12)
    float denom = std::abs(wi.z()) * m.z();
    return denom > 0.f ? G(wi, wo, m) * std::abs(wi.dot(m)) / denom : 0.f;
}

MicrofacetType read_distribution(const Props& props) {
    // Mitsuba's sample_visible picks how normals are sampled, not what the BSDF is: read (so a
    // scene that sets it loads) and ignored (docs/bsdfs.md "Deviations from Mitsuba 3").
    (void)props.get_bool("sample_visible", true);
    std::string name = props.get_string("distribution", "beckmann");
    if (name == "beckmann") return MicrofacetType::Beckmann;
    if (name == "ggx") return MicrofacetType::GGX;
    props.fail("distribution", "unknown microfacet distribution '" + name + "' (known: beckmann, ggx)");
}

float read_alpha(const Props& props) {
    for (const char* key : {"alpha_u", "alpha_v"})
        if (props.has(key)) props.fail(key, "anisotropic roughness is not supported; give a single 'alpha'");
    float alpha = props.get_float("alpha", 0.1f);
    if (!(alpha > 0.f)) props.fail("alpha", "roughness alpha must be > 0, got " + std::to_string(alpha));
    return alpha;
}

}  // namespace lpt
