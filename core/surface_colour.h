// A BSDF colour parameter that may be textured: what diffuse `reflectance` and the plastics'
// `diffuse_reflectance` hold. Three cases (docs/bsdfs.md, "Textured colours"):
//   * constant: one spectrum; fitted as one coefficient, key `<key>`;
//   * RGB bitmap (N = 3): the texel's linear RGB at the hit's uv; `<key>` replaces the image;
//   * latent bitmap (N ≠ 3, the paper's textured latents): ρ(uv) = g(uv) · s + o, where
//     g = 0.2126 R + 0.7152 G + 0.0722 B is the texel's linear Rec. 709 / sRGB luminance and
//     s, o are N-channel vectors fitted as keys `<key>.scale` and `<key>.offset`.
// ∂ρ/∂s = g(uv), ∂ρ/∂o = 1 per channel, so a BSDF's coefficient gradient is its ∂f/∂ρ at the
// hit times factor(): no division by anything.
#pragma once
#include "core/bsdf.h"
#include "core/texture.h"
#include <optional>
#include <string>
#include <vector>

namespace lpt {

template <int N>
class SurfaceColour {
public:
    SurfaceColour(const Props& props, const std::string& key, const Eigen::Array3f& default_rgb) : m_key(key) {
        Texture tex = texture_from_props(props, key, default_rgb);
        m_constant = spectrum_from_rgb<N>(tex.mean());  // the constant itself if untextured
        if (tex.is_constant()) return;
        if constexpr (N != 3) {
            // Before fitting, g · s reproduces the image's mean colour on average.
            const float g = luminance(tex.mean());
            m_scale = g > 0.f ? Spectrum<N>(m_constant / g) : Spectrum<N>(m_constant);
            m_offset = Spectrum<N>::Zero();
        }
        m_texture = std::move(tex);
    }

    /// g · s + o per channel when latent-textured, for one texel lookup.
    bool latent_textured() const { return N != 3 && m_texture.has_value(); }

    Spectrum<N> eval(const BSDFContext& ctx) const {
        if (!m_texture) return m_constant;
        if constexpr (N == 3) return m_texture->eval(ctx.uv);
        else return m_scale * luminance(m_texture->eval(ctx.uv)) + m_offset;
    }

    std::vector<std::string> keys() const {
        if (latent_textured()) return {m_key + ".scale", m_key + ".offset"};
        return {m_key};
    }
    /// Sets one of keys(); false if `key` is not one of them.
    bool set(const std::string& key, const Spectrum<N>& v) {
        if (latent_textured()) {
            if (key == m_key + ".scale") m_scale = v;
            else if (key == m_key + ".offset") m_offset = v;
            else return false;
            return true;
        }
        if (key != m_key) return false;
        m_constant = v;
        m_texture.reset();  // a fitted coefficient replaces an RGB image
        return true;
    }
    /// ∂ρ/∂c for c = keys()[sub], identical in every channel.
    float factor(const BSDFContext& ctx, int sub) const {
        return latent_textured() && sub == 0 ? luminance(m_texture->eval(ctx.uv)) : 1.f;
    }
    int key_count() const { return latent_textured() ? 2 : 1; }
    bool is_constant() const { return !m_texture.has_value(); }
    const Spectrum<N>& constant() const { return m_constant; }

private:
    std::string m_key;
    std::optional<Texture> m_texture;
    Spectrum<N> m_constant = Spectrum<N>::Zero(), m_scale = Spectrum<N>::Zero(), m_offset = Spectrum<N>::Zero();
};

}  // namespace lpt
