// Non-template Fresnel helpers: diffuse Fresnel reflectance by quadrature and the IOR keys.
// Equations: docs/bsdfs.md (1)-(4).
#include "core/bsdfs/fresnel.h"
#include <cctype>
#include <string>

namespace lpt {

float fresnel_diffuse_reflectance(float eta) {
    // Substituting s = mu^2 turns 2 mu dmu into ds; the midpoint rule on s then handles the kink
    // at the critical angle with O(h^2) error, ~1e-6 at this resolution.
    constexpr int kSteps = 4096;
    double sum = 0.0;
    for (int i = 0; i < kSteps; ++i) {
        double s = (i + 0.5) / kSteps;
        sum += fresnel_dielectric(float(std::sqrt(s)), eta).R;
    }
    return float(sum / kSteps);
}

namespace {

// Mitsuba's named IOR table (measured at ~589 nm, 0-20 °C), so scenes written for Mitsuba that
// name their media keep their meaning.
struct NamedIOR {
    const char* name;
    float value;
};
constexpr NamedIOR kNamedIORs[] = {
    {"vacuum", 1.0f},      {"helium", 1.000036f},        {"hydrogen", 1.000132f},
    {"air", 1.000277f},    {"carbon dioxide", 1.00045f}, {"water", 1.3330f},
    {"acetone", 1.36f},    {"ethanol", 1.361f},          {"carbon tetrachloride", 1.461f},
    {"glycerol", 1.4729f}, {"benzene", 1.501f},          {"silicone oil", 1.52045f},
    {"bromine", 1.661f},   {"water ice", 1.31f},         {"fused quartz", 1.458f},
    {"pyrex", 1.470f},     {"acrylic glass", 1.49f},     {"polypropylene", 1.49f},
    {"bk7", 1.5046f},      {"sodium chloride", 1.544f},  {"amber", 1.55f},
    {"pet", 1.5750f},      {"diamond", 2.419f},
};

float read_ior(const Props& props, const std::string& key, float def) {
    float v = def;
    props.mark_queried(key);
    auto it = props.values.find(key);
    if (it != props.values.end() && std::holds_alternative<std::string>(it->second)) {
        std::string name = std::get<std::string>(it->second);
        for (auto& c : name) c = char(std::tolower(static_cast<unsigned char>(c)));
        bool found = false;
        for (const auto& e : kNamedIORs) {
            if (name == e.name) {
                v = e.value;
                found = true;
            }
        }
        if (!found) {
            std::string known;
            for (const auto& e : kNamedIORs) known += (known.empty() ? "" : ", ") + std::string(e.name);
            props.fail(key, "unknown IOR name '" + name + "' (known: " + known + ")");
        }
    } else {
        v = props.get_float(key, def);
    }
    if (!(v > 0.f)) props.fail(key, "index of refraction must be > 0, got " + std::to_string(v));
    return v;
}

}  // namespace

float read_relative_ior(const Props& props, float default_int, float default_ext, bool require_distinct) {
    float int_ior = read_ior(props, "int_ior", default_int);
    float ext_ior = read_ior(props, "ext_ior", default_ext);
    if (require_distinct && int_ior == ext_ior)
        props.fail("int_ior", "int_ior and ext_ior must differ (index-matched rough interface)");
    return int_ior / ext_ior;
}

void read_conductor_ior_rgb(const Props& props, bool& perfect, Eigen::Array3f& eta, Eigen::Array3f& k) {
    std::string material = props.get_string("material", "none");
    if (material != "none")
        props.fail("material", "conductor material presets ('" + material +
                                   "') need a spectral IOR database, which latentpt does not ship; give eta and k "
                                   "(rgb) instead, or material \"none\" for a perfect mirror");
    perfect = !props.has("eta") && !props.has("k");
    eta = props.get_rgb("eta", Eigen::Array3f::Zero());
    k = props.get_rgb("k", Eigen::Array3f::Ones());
    if ((eta < 0.f).any()) props.fail("eta", "conductor eta must be >= 0");
    if ((k < 0.f).any()) props.fail("k", "conductor k must be >= 0");
}

}  // namespace lpt
