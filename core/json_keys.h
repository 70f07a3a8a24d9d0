// Keys of JSON objects people write by hand (scenes, edit sequences). A key the reader does not
// know is a typo ("max_dept", "azimut") that would otherwise leave its default in place without a
// word, so the readers refuse it; keys that start with '_' are comments ("_comment").
#pragma once
#include "core/error.h"
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lpt {

inline bool is_comment_key(const std::string& key) { return !key.empty() && key[0] == '_'; }

/// `obj` must be an object whose keys are all in `known` or comments; otherwise SceneError naming
/// `file` and the field ("camera.orbit.azimut", or the bare key at the top level).
inline void require_known_keys(const nlohmann::json& obj, const std::string& file, const std::string& field,
                               const std::vector<const char*>& known) {
    if (!obj.is_object()) throw SceneError(file, field, "expected an object, got " + std::string(obj.type_name()));
    for (const auto& [key, unused] : obj.items()) {
        if (is_comment_key(key)) continue;
        if (std::find_if(known.begin(), known.end(), [&](const char* k) { return key == k; }) != known.end()) continue;
        std::string list;
        for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
        throw SceneError(file, field.empty() ? key : field + "." + key, "unknown key (known here: " + list + ")");
    }
}

/// `j` as a float: SceneError naming `file` and `field` unless it is a JSON number that a float
/// holds finitely (1e39 is valid JSON and an infinite float).
inline float require_finite_number(const nlohmann::json& j, const std::string& file, const std::string& field) {
    if (!j.is_number()) throw SceneError(file, field, "expected a number, got " + std::string(j.type_name()));
    const float v = j.get<float>();
    if (!std::isfinite(v)) throw SceneError(file, field, "value is not finite");
    return v;
}

}  // namespace lpt
