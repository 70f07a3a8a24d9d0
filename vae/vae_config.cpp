#include "vae/vae_config.h"
#include "core/json_keys.h"
#include "core/json_number.h"
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace lpt {

VaeConfig read_vae_config(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw std::runtime_error(path + ": VAE config not found");
    std::ostringstream text;
    text << f.rdbuf();
    return parse_vae_config(text.str(), path);
}

VaeConfig parse_vae_config(const std::string& text, const std::string& path) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(path + ": malformed JSON: " + e.what());
    }
    if (!j.is_object()) throw std::runtime_error(path + ": expected a JSON object");
    // Every field but "name" (a description the exporters write) is required, so a misspelt one
    // fails as missing; an extra one (diffusers' "scaling_factor" beside "scale") would otherwise
    // pass as if it were read.
    require_known_keys(j, path, "", {"name", "channels", "downsample", "scale", "shift", "image_range", "latent"});
    auto field = [&](const char* k) -> const nlohmann::json& {
        if (!j.contains(k)) throw std::runtime_error(path + ": missing field '" + k + "'");
        return j[k];
    };
    VaeConfig c;
    try {
        c.convention.channels = json_int(field("channels"), path, "channels", 1, 4096);
        c.convention.downsample = json_int(field("downsample"), path, "downsample", 1, 4096);
        c.convention.scale = field("scale").get<float>();
        c.convention.shift = field("shift").get<float>();
        const auto range = field("image_range").get<std::vector<float>>();
        if (range.size() != 2 || !(range[1] > range[0]) || !std::isfinite(range[1] - range[0]))
            throw std::runtime_error(path + ": field 'image_range' must be [low, high] with low < high");
        c.image_lo = range[0];
        c.image_hi = range[1];
        const std::string latent = field("latent").get<std::string>();
        if (latent != "raw" && latent != "model")
            throw std::runtime_error(path + ": field 'latent' must be \"raw\" or \"model\", got \"" + latent + "\"");
        c.raw_latent = latent == "raw";
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(path + ": wrong type of a field: " + e.what());
    }
    const LatentConvention& v = c.convention;
    if (v.channels < 1 || v.downsample < 1)
        throw std::runtime_error(path + ": fields 'channels' and 'downsample' must be >= 1");
    if (v.scale == 0.f || !std::isfinite(v.scale) || !std::isfinite(v.shift))
        throw std::runtime_error(path + ": field 'scale' must be finite and non-zero, 'shift' finite");
    return c;
}

}  // namespace lpt
