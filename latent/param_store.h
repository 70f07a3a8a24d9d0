// ParamStore: every learnable value of the latent renderer in flat buffers, addressed by named
// slices ("<shape id>.La", "<shape id>.bsdf.reflectance", "background"). The optimiser sees
// only the flat raw buffer; renderers read `value` (raw mapped through the slice's map) and
// write d_loss/d_value into `grad_value`; backward() applies the maps' derivatives.
// Maps and their derivatives: docs/params.md.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace lpt {

enum class ParamMap {
    Identity,  ///< value = raw; raw clamped to [lo, hi] after each step (public code: [-6, 6])
    Sigmoid,   ///< value = 1 / (1 + exp(-raw)) (public code's reflectances)
    PosNeg,    ///< value = pos - neg, both raw parts clamped to [lo, hi] (paper text: [0, hi])
    Gain,      ///< value = exp(g) * u: raw = (u, g), u clamped to [lo, hi], one log-gain g in [kGainLo, kGainHi]
};

/// Range of a Gain slice's log-gain: e^12 ≈ 1.6e5 lets an emitter whose light reaches the image
/// only after bounces grow far past the [-6, 6] of its vector (docs/params.md (4)).
constexpr float kGainLo = -12.f, kGainHi = 12.f;

const char* to_string(ParamMap m);
ParamMap param_map_from_string(const std::string& s);  ///< throws std::invalid_argument

struct ParamSlice {
    std::string name;  ///< unique, "<shape id>.<kind>"
    std::string kind;  ///< "Le", "La", "Lc", "reflectance", "specular_reflectance", "alpha", "background", ...
    ParamMap map = ParamMap::Identity;
    int channels = 0;
    size_t raw_offset = 0;  ///< PosNeg holds `channels` pos entries then `channels` neg entries
    size_t value_offset = 0;
    float lo = -6.f, hi = 6.f;
    size_t raw_size() const {
        return map == ParamMap::PosNeg ? 2 * size_t(channels) : size_t(channels) + (map == ParamMap::Gain ? 1 : 0);
    }
    /// Raw entries of the vector itself: all but a Gain slice's trailing log-gain.
    size_t vector_raw_size() const { return map == ParamMap::Gain ? size_t(channels) : raw_size(); }
    /// Why raw entry k cannot hold v, or "" if it can: a Gain slice's log-gain must lie in
    /// [kGainLo, kGainHi] (e^g of a larger one overflows); the other entries take any value.
    std::string raw_problem(size_t k, float v) const;
};

class ParamStore {
public:
    /// Adds a slice (raw zero-initialised); returns its index. Throws on a duplicate name.
    int add(const std::string& name, const std::string& kind, ParamMap map, int channels, float lo, float hi);
    int find(const std::string& name) const;  ///< -1 if absent
    size_t slice_count() const { return m_slices.size(); }
    const ParamSlice& slice(int i) const { return m_slices[i]; }

    std::vector<float>& raw() { return m_raw; }
    const std::vector<float>& raw() const { return m_raw; }
    std::vector<float>& grad_raw() { return m_grad_raw; }
    const std::vector<float>& grad_raw() const { return m_grad_raw; }
    const float* value(int slice) const { return m_value.data() + m_slices[slice].value_offset; }
    float* grad_value(int slice) { return m_grad_value.data() + m_slices[slice].value_offset; }
    const std::vector<float>& values() const { return m_value; }
    std::vector<float>& grad_values() { return m_grad_value; }

    /// Sets the raw parameters so that value(slice) == v (v within the map's range; PosNeg puts
    /// a positive v in pos and a negative one in neg). Throws if the map cannot reach v.
    void set_value(int slice, const float* v);
    /// value = map(raw) for every slice.
    void update_values();
    /// grad_raw = grad_value * d map / d raw (grad_value left as is).
    void backward();
    void zero_grad();
    /// Projects raw back into each slice's [lo, hi] (after an optimiser step).
    void clamp_raw();
    /// Uniform random raw values in [a, b] for every slice of `kind` (deterministic in seed); a Gain
    /// slice's log-gain starts at 0, so its initial values are those of an Identity slice.
    void init_uniform(const std::string& kind, float a, float b, uint64_t seed);

    /// Human-readable JSON: {"slices": [{"name", "kind", "map", "lo", "hi", "raw": [...], "value": [...]}]}.
    std::string to_json() const;
    /// Reads raw values back for slices that exist here; unknown names or wrong sizes throw
    /// std::runtime_error naming `file` and the slice.
    void load_json(const std::string& text, const std::string& file);

private:
    std::vector<ParamSlice> m_slices;
    std::vector<float> m_raw, m_grad_raw, m_value, m_grad_value;
};

}  // namespace lpt
