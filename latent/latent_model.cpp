#include "latent/latent_model.h"
#include "core/sampler.h"
#include <algorithm>
#include <stdexcept>

namespace lpt {

Parameterisation parameterisation_from_string(const std::string& s) {
    if (s == "paper") return Parameterisation::Paper;
    if (s == "code") return Parameterisation::Code;
    if (s == "classic") return Parameterisation::Classic;
    if (s == "gain") return Parameterisation::Gain;
    throw std::invalid_argument("unknown parameterisation '" + s + "' (known: paper, code, classic, gain)");
}

namespace {

struct SliceSpec {
    ParamMap map;
    float lo, hi, init_a, init_b;
};

/// docs/params.md: the two parameterisations, per kind of vector.
SliceSpec spec_for(Parameterisation p, bool reflectance_like) {
    if (p == Parameterisation::Code || p == Parameterisation::Gain)
        return reflectance_like ? SliceSpec{ParamMap::Sigmoid, -1e30f, 1e30f, -1.f, 1.f}
                                : SliceSpec{ParamMap::Identity, -6.f, 6.f, -0.1f, 0.1f};
    if (p == Parameterisation::Classic)  // non-negative; radiances start small so the render starts inside (0, 1)
        return reflectance_like ? SliceSpec{ParamMap::Sigmoid, -1e30f, 1e30f, -1.f, 1.f}
                                : SliceSpec{ParamMap::Identity, 0.f, 1e4f, 0.f, 0.2f};
    return reflectance_like ? SliceSpec{ParamMap::PosNeg, 0.f, 1.f, 0.f, 1.f}
                            : SliceSpec{ParamMap::PosNeg, 0.f, 1e30f, 0.f, 1.f};
}

}  // namespace

LatentModel::LatentModel(const Scene& scene, Parameterisation p, uint64_t seed) : m_scene(scene) {
    m_spectra = SceneSpectra<kLatentChannels>::per_shape(m_scene);
    m_slots.resize(m_scene.shapes.size());
    auto add = [&](const std::string& name, const std::string& kind, bool refl) {
        SliceSpec s = spec_for(p, refl);
        // docs/params.md (4): Gain is Code with one learnable log-gain on each emitter's L̃e
        const ParamMap map = p == Parameterisation::Gain && kind == "Le" ? ParamMap::Gain : s.map;
        return m_params.add(name, kind, map, kLatentChannels, s.lo, s.hi);
    };
    for (size_t i = 0; i < m_scene.shapes.size(); ++i) {
        const Shape& shape = m_scene.shapes[i];
        ShapeSlots& sl = m_slots[i];
        if (shape.emitter >= 0) sl.Le = add(shape.id + ".Le", "Le", false);
        const BSDF<kLatentChannels>& bsdf = m_spectra.bsdf_of(int(i));
        if (!bsdf.is_delta()) {
            sl.La = add(shape.id + ".La", "La", false);
            sl.Lc = add(shape.id + ".Lc", "Lc", false);
        }
        for (const std::string& key : bsdf.spectral_keys())
            sl.bsdf.emplace_back(key, add(shape.id + ".bsdf." + key, "reflectance", true));
        for (const std::string& key : bsdf.scalar_keys())
            sl.scalar.emplace_back(key,
                                   m_params.add(shape.id + ".bsdf." + key, key, ParamMap::Sigmoid, 1, -1e30f, 1e30f));
    }
    if (m_scene.environment >= 0) m_env_slot = add("environment.Le", "Le", false);
    m_background = add("background", "background", false);

    // Deterministic init: one seed, a distinct stream per kind.
    const SliceSpec radiance = spec_for(p, false), refl = spec_for(p, true);
    uint64_t k = 0;
    for (const char* kind : {"Le", "La", "Lc", "background"})
        m_params.init_uniform(kind, radiance.init_a, radiance.init_b, mix64(seed + ++k));
    m_params.init_uniform("reflectance", refl.init_a, refl.init_b, mix64(seed + ++k));

    // Scalars (roughness) start where the scene file puts them, inside the sigmoid's range.
    for (size_t i = 0; i < m_scene.shapes.size(); ++i)
        for (const auto& [key, slice] : m_slots[i].scalar) {
            float v = std::clamp(m_spectra.bsdf_of(int(i)).get_scalar(key), 1e-3f, 0.999f);
            m_params.set_value(slice, &v);
        }

    m_terms.La.assign(m_scene.shapes.size(), Latent::Zero());
    m_terms.Lc.assign(m_scene.shapes.size(), Latent::Zero());
    sync();
}

void LatentModel::sync() {
    m_params.update_values();
    auto vec = [&](int slice) { return Eigen::Map<const Latent>(m_params.value(slice)); };
    for (size_t i = 0; i < m_scene.shapes.size(); ++i) {
        const ShapeSlots& sl = m_slots[i];
        const Shape& shape = m_scene.shapes[i];
        if (sl.Le >= 0) m_spectra.radiance[shape.emitter] = vec(sl.Le);
        m_terms.La[i] = sl.La >= 0 ? Latent(vec(sl.La)) : Latent::Zero();
        m_terms.Lc[i] = sl.Lc >= 0 ? Latent(vec(sl.Lc)) : Latent::Zero();
        for (const auto& [key, slice] : sl.bsdf) m_spectra.bsdf_of(int(i)).set_spectral(key, vec(slice));
        for (const auto& [key, slice] : sl.scalar) m_spectra.bsdf_of(int(i)).set_scalar(key, *m_params.value(slice));
    }
    if (m_env_slot >= 0) m_spectra.radiance[m_scene.environment] = vec(m_env_slot);
    m_terms.background = vec(m_background);
}

void LatentModel::scale_emission(float k) {
    // only the entries sync() writes, so that the next sync() restores them all
    for (size_t i = 0; i < m_scene.shapes.size(); ++i)
        if (m_slots[i].Le >= 0) m_spectra.radiance[m_scene.shapes[i].emitter] *= k;
    if (m_env_slot >= 0) m_spectra.radiance[m_scene.environment] *= k;
}

}  // namespace lpt
