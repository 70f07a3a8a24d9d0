// BSDF registry: the explicit table from scene `type` string to factory (static
// self-registration would vanish from the static library; STYLE.md section 3). Each factory
// lives in core/bsdfs/<type>.cpp and is explicitly instantiated there for N = 3 and N = 16.
#include "core/bsdf.h"
#include "core/texture.h"
#include <string>

namespace lpt {

template <int N>
std::unique_ptr<BSDF<N>> make_diffuse_bsdf(const Props&);
template <int N>
std::unique_ptr<BSDF<N>> make_conductor_bsdf(const Props&);
template <int N>
std::unique_ptr<BSDF<N>> make_roughconductor_bsdf(const Props&);
template <int N>
std::unique_ptr<BSDF<N>> make_dielectric_bsdf(const Props&);
template <int N>
std::unique_ptr<BSDF<N>> make_roughdielectric_bsdf(const Props&);
template <int N>
std::unique_ptr<BSDF<N>> make_plastic_bsdf(const Props&);
template <int N>
std::unique_ptr<BSDF<N>> make_roughplastic_bsdf(const Props&);
template <int N>
std::unique_ptr<BSDF<N>> make_twosided_bsdf(const Props&);

namespace {

template <int N>
struct BSDFEntry {
    const char* type;
    std::unique_ptr<BSDF<N>> (*make)(const Props&);
};

template <int N>
const BSDFEntry<N> kBSDFTable[] = {
    {"diffuse", &make_diffuse_bsdf<N>},
    {"conductor", &make_conductor_bsdf<N>},
    {"roughconductor", &make_roughconductor_bsdf<N>},
    {"dielectric", &make_dielectric_bsdf<N>},
    {"roughdielectric", &make_roughdielectric_bsdf<N>},
    {"plastic", &make_plastic_bsdf<N>},
    {"roughplastic", &make_roughplastic_bsdf<N>},
    {"twosided", &make_twosided_bsdf<N>},
};

}  // namespace

template <int N>
std::unique_ptr<BSDF<N>> make_bsdf(const Props& props) {
    for (const auto& e : kBSDFTable<N>)
        if (props.type == e.type) return e.make(props);
    std::string known;
    for (const auto& e : kBSDFTable<N>) known += (known.empty() ? "" : ", ") + std::string(e.type);
    throw SceneError(props.file, props.where.empty() ? "type" : props.where + ".type",
                     "unknown BSDF type '" + props.type + "' (known: " + known + ")");
}

namespace {

/// The colours of a scene file's BSDFs, which must not be negative there (latent BSDFs take
/// signed values under the same keys, so the BSDFs themselves accept them).
constexpr const char* kColourKeys[] = {"reflectance", "diffuse_reflectance", "specular_reflectance",
                                       "specular_transmittance"};

void require_non_negative_colours(const Props& props) {
    for (const auto& [key, value] : props.values) {
        if (const auto* child = std::get_if<std::shared_ptr<Props>>(&value)) {
            if (*child && (*child)->type != "bitmap") require_non_negative_colours(**child);
            continue;
        }
        for (const char* colour : kColourKeys)
            if (key == colour) props.get_colour(key);
    }
}

}  // namespace

void check_bsdf_description(const Props& props) {
    PropsReadLog read;
    try {
        make_bsdf<3>(props);
    } catch (const SceneError& e) {
        // A bitmap under a key the BSDF reads as a plain colour: say so rather than "expected an
        // rgb triple". Only here: a bitmap under a key nobody reads is a typo (below).
        throw explain_texture_error(props, e);
    }
    read.require_all_read(props);
    require_non_negative_colours(props);
}

template std::unique_ptr<BSDF<3>> make_bsdf<3>(const Props&);
template std::unique_ptr<BSDF<16>> make_bsdf<16>(const Props&);

}  // namespace lpt
