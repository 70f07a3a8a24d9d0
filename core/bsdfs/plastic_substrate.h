// The diffuse substrate under a dielectric coating, shared by plastic and roughplastic: its
// colour (constant, or a bitmap for N = 3), the base colour after internal reflections
// ρ̃ = ρ / (1 − Fdr) or, nonlinear, ρ / (1 − ρ·Fdr) (docs/bsdfs.md (23)), and the derivatives
// ∂ρ̃/∂ρ (34) and ∂ρ̃/∂α through ∂Fdr/∂α (42). The coating decides Fdr.
#pragma once
#include "core/props.h"
#include "core/spectrum.h"
#include "core/texture.h"
#include "core/bsdf.h"
#include <optional>

namespace lpt {

template <int N>
class PlasticSubstrate {
public:
    /// Reads diffuse_reflectance (rgb or bitmap; default 0.5) and nonlinear (default false).
    explicit PlasticSubstrate(const Props& props) : m_nonlinear(props.get_bool("nonlinear", false)) {
        Texture tex = texture_from_props(props, "diffuse_reflectance", Eigen::Array3f::Constant(0.5f));
        m_diffuse = spectrum_from_rgb<N>(tex.mean());  // latent channels: the mean (issue 7)
        if constexpr (N == 3)
            if (!tex.is_constant()) m_texture = std::move(tex);
    }

    /// The coating's internal diffuse reflectance and its roughness derivative.
    void set_internal_reflectance(float fdr, float dfdr_dalpha = 0.f) {
        m_fdr = fdr;
        m_dfdr = dfdr_dalpha;
        update();
    }
    /// A fitted colour replaces the image (for N = 3 too).
    void set_colour(const Spectrum<N>& d) {
        m_diffuse = d;
        m_texture.reset();
        update();
    }

    /// ρ̃ at this lookup: the texel's for a bitmap (N = 3), else the constant's.
    Spectrum<N> base(const BSDFContext& ctx) const {
        if constexpr (N == 3)
            if (m_texture) return base_of(m_texture->eval(ctx.uv));
        return m_base;
    }
    Spectrum<N> albedo(const BSDFContext& ctx) const {
        if constexpr (N == 3)
            if (m_texture) return m_texture->eval(ctx.uv);
        return m_diffuse;
    }
    /// Derivatives of the constant (latent) base colour.
    const Spectrum<N>& base_constant() const { return m_base; }
    const Spectrum<N>& d_base_d_colour() const { return m_base_grad; }
    const Spectrum<N>& d_base_d_alpha() const { return m_base_dalpha; }

private:
    Spectrum<N> base_of(const Spectrum<N>& d) const {
        return m_nonlinear ? Spectrum<N>(d / (1.f - d * m_fdr)) : Spectrum<N>(d / (1.f - m_fdr));
    }
    void update() {
        m_base = base_of(m_diffuse);
        if (m_nonlinear) {
            Spectrum<N> denom = 1.f - m_diffuse * m_fdr;
            m_base_grad = 1.f / (denom * denom);
            m_base_dalpha = m_diffuse * m_diffuse * m_dfdr / (denom * denom);
        } else {
            m_base_grad = Spectrum<N>::Constant(1.f / (1.f - m_fdr));
            m_base_dalpha = m_diffuse * (m_dfdr / ((1.f - m_fdr) * (1.f - m_fdr)));
        }
    }

    bool m_nonlinear;
    float m_fdr = 0.f, m_dfdr = 0.f;
    std::optional<Texture> m_texture;  ///< only ever set for N = 3
    Spectrum<N> m_diffuse, m_base = Spectrum<N>::Zero(), m_base_grad = Spectrum<N>::Zero(), m_base_dalpha = Spectrum<N>::Zero();
};

}  // namespace lpt
