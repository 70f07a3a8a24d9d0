// Props: a parsed plugin description (type + named values), the common currency between
// scene-file loaders (JSON, Mitsuba XML) and plugin factories. Getters throw SceneError naming
// `where` + the key, so a bad value is reported against the file and field it came from.
#pragma once
#include "core/error.h"
#include "core/transform.h"
#include <Eigen/Core>
#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

namespace lpt {

struct Props;

using PropValue = std::variant<bool, float, std::string, Eigen::Array3f, Transform, std::shared_ptr<Props>>;

struct Props {
    std::string type;
    std::string file;   ///< source file, for error messages
    std::string where;  ///< field path of this object inside `file` (e.g. "materials.white")
    std::map<std::string, PropValue> values;

    bool has(const std::string& key) const { return values.count(key) != 0; }
    [[noreturn]] void fail(const std::string& key, const std::string& msg) const;

    float get_float(const std::string& key, float def) const;
    float get_float(const std::string& key) const;
    bool get_bool(const std::string& key, bool def) const;
    std::string get_string(const std::string& key, const std::string& def) const;
    std::string get_string(const std::string& key) const;
    /// An rgb triple; a float value is broadcast to three channels.
    Eigen::Array3f get_rgb(const std::string& key, const Eigen::Array3f& def) const;
    Eigen::Array3f get_rgb(const std::string& key) const;
    Transform get_transform(const std::string& key, const Transform& def) const;
    /// Nested object (e.g. the BSDF inside `twosided`); nullptr if absent.
    std::shared_ptr<Props> get_child(const std::string& key) const;
};

}  // namespace lpt
