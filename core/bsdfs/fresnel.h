// Fresnel reflectance of a smooth interface, and the IOR-valued Props keys shared by the
// dielectric-, conductor- and plastic-type plugins.
//   - fresnel_dielectric: real relative IOR, returns R, the signed refracted cosine and the
//     relative IORs seen from the incident side.            docs/bsdfs.md (1)-(2)
//   - fresnel_conductor: complex IOR eta + i k per channel.  docs/bsdfs.md (3)
//   - fresnel_diffuse_reflectance: cosine-weighted hemispherical average of (1), docs/bsdfs.md (4)
// Keys read here (units: dimensionless indices of refraction):
//   int_ior, ext_ior  float or a material name from Mitsuba's IOR table ("bk7", "air", ...);
//                     defaults are chosen by the calling plugin; must be > 0.
//   eta, k, material  conductor complex IOR (rgb, Mitsuba 3 defaults eta = 0, k = 1 when one of
//                     them is given); material "none" or absent with no eta/k = perfect mirror.
#pragma once
#include "core/props.h"
#include "core/spectrum.h"
#include <cmath>

namespace lpt {

struct FresnelDielectric {
    float R = 1.f;       ///< unpolarised reflectance in [0, 1] (1 under total internal reflection)
    float cos_t = 0.f;   ///< cosine of the refracted direction, sign opposite to cos_i (0 under TIR)
    float eta_it = 1.f;  ///< eta_t / eta_i as seen from the incident side
    float eta_ti = 1.f;  ///< 1 / eta_it
};

/// cos_i: cosine of the incident direction with the interface normal; its sign says which side
/// the incident direction is on (> 0: exterior). eta = int_ior / ext_ior.  docs/bsdfs.md (1)-(2)
inline FresnelDielectric fresnel_dielectric(float cos_i, float eta) {
    FresnelDielectric f;
    bool outside = cos_i >= 0.f;
    f.eta_it = outside ? eta : 1.f / eta;
    f.eta_ti = outside ? 1.f / eta : eta;
    float cos_t2 = 1.f - (1.f - cos_i * cos_i) * f.eta_ti * f.eta_ti;
    float ci = std::abs(cos_i);
    float ct = std::sqrt(std::max(0.f, cos_t2));
    if (eta == 1.f) {
        f.R = 0.f;
    } else if (ci == 0.f || cos_t2 <= 0.f) {
        f.R = 1.f;  // grazing incidence, or total internal reflection (ct = 0)
    } else {
        float a_s = (ci - f.eta_it * ct) / (ci + f.eta_it * ct);
        float a_p = (ct - f.eta_it * ci) / (ct + f.eta_it * ci);
        f.R = 0.5f * (a_s * a_s + a_p * a_p);
    }
    f.cos_t = cos_i >= 0.f ? -ct : ct;
    return f;
}

/// Unpolarised conductor reflectance for relative complex IOR eta + i k, per channel; cos_i is
/// taken by magnitude. Mitsuba 3's closed form.  docs/bsdfs.md (3)
template <int N>
Spectrum<N> fresnel_conductor(float cos_i, const Spectrum<N>& eta, const Spectrum<N>& k) {
    float c2 = std::min(1.f, cos_i * cos_i), s2 = 1.f - c2, s4 = s2 * s2;
    Spectrum<N> t1 = eta * eta - k * k - s2;
    Spectrum<N> a2pb2 = (t1 * t1 + 4.f * k * k * eta * eta).sqrt();
    Spectrum<N> a = (0.5f * (a2pb2 + t1)).max(0.f).sqrt();
    Spectrum<N> term1 = a2pb2 + c2;
    Spectrum<N> term2 = 2.f * std::sqrt(c2) * a;
    Spectrum<N> r_s = (term1 - term2) / (term1 + term2);
    Spectrum<N> term3 = a2pb2 * c2 + s4;
    Spectrum<N> term4 = term2 * s2;
    Spectrum<N> r_p = r_s * (term3 - term4) / (term3 + term4);
    return 0.5f * (r_s + r_p);
}

/// 2 ∫_0^1 R(mu; eta) mu dmu by quadrature (accurate to ~1e-6, TIR included).  docs/bsdfs.md (4)
float fresnel_diffuse_reflectance(float eta);

/// int_ior / ext_ior from Props (numbers or Mitsuba IOR names), each validated > 0.
/// require_distinct: index-matched interfaces are rejected (rough models divide by eta - 1).
float read_relative_ior(const Props& props, float default_int, float default_ext, bool require_distinct);

/// Complex conductor IOR; `perfect` when no eta/k is given (F = 1 exactly, no Fresnel call).
template <int N>
struct ConductorIOR {
    bool perfect = true;
    Spectrum<N> eta = Spectrum<N>::Zero();
    Spectrum<N> k = Spectrum<N>::Ones();
    Spectrum<N> fresnel(float cos_i) const {
        return perfect ? Spectrum<N>::Ones() : fresnel_conductor<N>(cos_i, eta, k);
    }
};

/// Validates `material` (only "none" is accepted: no spectral IOR database ships with latentpt)
/// and returns the rgb eta/k (Mitsuba 3 defaults eta = 0, k = 1 when only one is given).
void read_conductor_ior_rgb(const Props& props, bool& perfect, Eigen::Array3f& eta, Eigen::Array3f& k);

template <int N>
ConductorIOR<N> read_conductor_ior(const Props& props) {
    ConductorIOR<N> ior;
    Eigen::Array3f eta, k;
    read_conductor_ior_rgb(props, ior.perfect, eta, k);
    ior.eta = spectrum_from_rgb<N>(eta);
    ior.k = spectrum_from_rgb<N>(k);
    return ior;
}

}  // namespace lpt
