// The diffuse substrate under a dielectric coating, shared by plastic and roughplastic: its
// colour ρ (constant, RGB bitmap, or latent g·s + o: core/surface_colour.h), the base colour
// after internal reflections ρ̃ = ρ / (1 − Fdr) or, nonlinear, ρ / (1 − ρ·Fdr) (docs/bsdfs.md
// (23)), and the derivatives ∂ρ̃/∂c (34) for each colour coefficient c and ∂ρ̃/∂α through
// ∂Fdr/∂α (42). The coating decides Fdr. Constant colours cache ρ̃ and its derivatives; textured
// ones evaluate them at the hit's ρ(uv).
#pragma once
#include "core/bsdf.h"
#include "core/props.h"
#include "core/spectrum.h"
#include "core/surface_colour.h"

namespace lpt {

template <int N>
class PlasticSubstrate {
public:
    /// Reads diffuse_reflectance (rgb or bitmap; default 0.5) and nonlinear (default false).
    explicit PlasticSubstrate(const Props& props)
        : m_nonlinear(props.get_bool("nonlinear", false)),
          m_colour(props, "diffuse_reflectance", Eigen::Array3f::Constant(0.5f)) {}

    /// The coating's internal diffuse reflectance and its roughness derivative.
    void set_internal_reflectance(float fdr, float dfdr_dalpha = 0.f) {
        m_fdr = fdr;
        m_dfdr = dfdr_dalpha;
        update();
    }
    /// The colour's fitting keys (diffuse_reflectance, or its .scale and .offset).
    std::vector<std::string> keys() const { return m_colour.keys(); }
    int key_count() const { return m_colour.key_count(); }
    /// Sets one of keys(); false if `key` is not one of them.
    bool set(const std::string& key, const Spectrum<N>& v) {
        if (!m_colour.set(key, v)) return false;
        update();
        return true;
    }

    /// ρ̃ at this lookup.
    Spectrum<N> base(const BSDFContext& ctx) const {
        return m_colour.is_constant() ? m_base : base_of(m_colour.eval(ctx));
    }
    Spectrum<N> albedo(const BSDFContext& ctx) const { return m_colour.eval(ctx); }
    /// ∂ρ̃/∂c for c = keys()[sub]: ∂ρ̃/∂ρ at this lookup's ρ times ∂ρ/∂c.
    Spectrum<N> d_base(const BSDFContext& ctx, int sub) const {
        if (m_colour.is_constant()) return m_base_grad;
        return d_base_d_rho(m_colour.eval(ctx)) * m_colour.factor(ctx, sub);
    }
    /// ∂ρ̃/∂α at this lookup.
    Spectrum<N> d_base_d_alpha(const BSDFContext& ctx) const {
        return m_colour.is_constant() ? m_base_dalpha : d_base_d_alpha_at(m_colour.eval(ctx));
    }

private:
    Spectrum<N> base_of(const Spectrum<N>& d) const {
        return m_nonlinear ? Spectrum<N>(d / (1.f - d * m_fdr)) : Spectrum<N>(d / (1.f - m_fdr));
    }
    Spectrum<N> d_base_d_rho(const Spectrum<N>& d) const {
        if (!m_nonlinear) return Spectrum<N>::Constant(1.f / (1.f - m_fdr));
        Spectrum<N> denom = 1.f - d * m_fdr;
        return 1.f / (denom * denom);
    }
    Spectrum<N> d_base_d_alpha_at(const Spectrum<N>& d) const {
        if (!m_nonlinear) return d * (m_dfdr / ((1.f - m_fdr) * (1.f - m_fdr)));
        Spectrum<N> denom = 1.f - d * m_fdr;
        return d * d * m_dfdr / (denom * denom);
    }
    void update() {
        m_base = base_of(m_colour.constant());
        m_base_grad = d_base_d_rho(m_colour.constant());
        m_base_dalpha = d_base_d_alpha_at(m_colour.constant());
    }

    bool m_nonlinear;
    float m_fdr = 0.f, m_dfdr = 0.f;
    SurfaceColour<N> m_colour;
    Spectrum<N> m_base = Spectrum<N>::Zero(), m_base_grad = Spectrum<N>::Zero(), m_base_dalpha = Spectrum<N>::Zero();
};

}  // namespace lpt
