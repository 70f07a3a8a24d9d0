// The rough coating's tables for roughplastic (docs/bsdfs.md (26), (27), (42), (46)): the
// transmittance T(μ) and the specular albedo A(μ) of a rough dielectric interface (Mitsuba's
// eval_transmittance / eval_reflectance), tabulated over 64 cosines μ_j = j/63, with their exact
// α-derivatives.
//
// Why a cache over α: a fit moves α every Adam step, and the direct quadrature costs 40–90 ms
// per (t, ∂t/∂α) pair; 33 rough-plastic shapes (dining-room) spent > 90% of each step there.
// The tables are therefore computed once per node α_k = 1e-4·exp(k/8) and per (distribution, η),
// shared by every BSDF and thread, and interpolated in s = ln α by cubic Hermite splines whose
// node slopes are the exact derivative integral: t is C¹ in α, accurate to O(Δs⁴) between
// nodes, and ∂t/∂α is the exact derivative of the interpolated t (finite differences of the
// rendered BSDF match its gradient to rounding).
#pragma once
#include "core/bsdfs/microfacet.h"
#include <algorithm>
#include <array>

namespace lpt {

constexpr int kTransmittanceRes = 64;

/// Which lobe of the interface a table integrates: the refracted energy T(μ), the reflected A(μ),
/// or the reflected lobe without Fresnel, D G / (4 μ) alone (its albedo: what a Fresnel-free
/// microfacet BSDF such as Cycles' Glossy reflects; cycles_approximation.h).
enum class CoatingLobe { Transmission, Reflection, Glossy };

/// One lobe's albedo over μ_j (named after its main use, the transmittance t).
struct TransmittanceTable {
    std::array<float, kTransmittanceRes> t{};   ///< the lobe's albedo at μ_j, clamped to [0, 1]
    std::array<float, kTransmittanceRes> dt{};  ///< its ∂/∂α at μ_j; 0 where t is clamped
    float mean = 0.f;                           ///< T̄ = 2 ∫ t(μ) μ dμ of the piecewise-linear t (27)
    float dmean = 0.f;                          ///< ∂T̄/∂α, the same functional of dt
};

/// A lobe's table at roughness alpha (> 0) for relative IOR eta, interpolated from cached nodes
/// (docs/bsdfs.md (46)). Thread-safe; deterministic (a node depends only on its key).
TransmittanceTable rough_lobe_table(MicrofacetType type, float eta, float alpha, CoatingLobe lobe);
inline TransmittanceTable rough_transmittance(MicrofacetType type, float eta, float alpha) {
    return rough_lobe_table(type, eta, alpha, CoatingLobe::Transmission);
}
inline TransmittanceTable rough_reflectance(MicrofacetType type, float eta, float alpha) {
    return rough_lobe_table(type, eta, alpha, CoatingLobe::Reflection);
}

/// A lobe's table by direct quadrature at alpha (uncached, 40–90 ms): the nodes of the above,
/// and the reference its interpolation is tested against. dt here is the quadrature of the
/// exact derivative integral (42), not the slope of t's quadrature.
TransmittanceTable rough_lobe_table_direct(MicrofacetType type, float eta, float alpha, CoatingLobe lobe);
inline TransmittanceTable rough_transmittance_direct(MicrofacetType type, float eta, float alpha) {
    return rough_lobe_table_direct(type, eta, alpha, CoatingLobe::Transmission);
}

/// Nodes computed so far by rough_transmittance (all distributions and IORs): for tests.
size_t rough_transmittance_nodes_built();

/// Linear interpolation over μ_j = j/63 (as Mitsuba's lerp_gather); μ is clamped to [0, 1].
inline float interpolate_mu(const std::array<float, kTransmittanceRes>& table, float mu) {
    float x = std::clamp(mu, 0.f, 1.f) * (kTransmittanceRes - 1);
    int j = std::min(int(x), kTransmittanceRes - 2);
    float w = x - float(j);
    return (1.f - w) * table[j] + w * table[j + 1];
}

}  // namespace lpt
