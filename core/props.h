// Props: a parsed plugin description (type + named values), the common currency between
// scene-file loaders (JSON, Mitsuba XML) and plugin factories. Getters throw SceneError naming
// `where` + the key, so a bad value is reported against the file and field it came from.
#pragma once
#include "core/error.h"
#include "core/transform.h"
#include <Eigen/Core>
#include <map>
#include <memory>
#include <set>
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
    /// Tells this thread's PropsReadLog, if one is open, that a reader asked for `key`. The
    /// getters do; a reader that looks into `values` itself calls it.
    void mark_queried(const std::string& key) const;
    [[noreturn]] void fail(const std::string& key, const std::string& msg) const;

    float get_float(const std::string& key, float def) const;
    float get_float(const std::string& key) const;
    bool get_bool(const std::string& key, bool def) const;
    std::string get_string(const std::string& key, const std::string& def) const;
    std::string get_string(const std::string& key) const;
    /// An rgb triple; a float value is broadcast to three channels.
    Eigen::Array3f get_rgb(const std::string& key, const Eigen::Array3f& def) const;
    Eigen::Array3f get_rgb(const std::string& key) const;
    /// An rgb value of a scene file that is physically non-negative (a radiance, a reflectance):
    /// a negative channel is an error rather than light from nowhere. BSDFs read get_rgb, since
    /// latent BSDFs are made from Props with signed values; check_bsdf_description checks theirs.
    Eigen::Array3f get_colour(const std::string& key, const Eigen::Array3f& def) const;
    Eigen::Array3f get_colour(const std::string& key) const;
    Transform get_transform(const std::string& key, const Transform& def) const;
    /// Nested object (e.g. the BSDF inside `twosided`); nullptr if absent.
    std::shared_ptr<Props> get_child(const std::string& key) const;
};

/// While alive, records which keys of which Props this thread's readers ask for (there or not:
/// what the plugin reads), so a loader can refuse the values nobody read, such as a misspelt
/// 'reflectanse' that would leave the default in place without a word (Mitsuba 3 refuses
/// unreferenced properties too). Thread-local, so renders reading Props elsewhere are untouched.
class PropsReadLog {
public:
    PropsReadLog();
    ~PropsReadLog();
    PropsReadLog(const PropsReadLog&) = delete;
    PropsReadLog& operator=(const PropsReadLog&) = delete;

    void note(const Props* props, const std::string& key) { m_read[props].insert(key); }
    /// Fails on the first value of `props` that no reader asked for; nested objects that were
    /// read are checked the same way.
    void require_all_read(const Props& props) const;

private:
    std::map<const Props*, std::set<std::string>> m_read;
    PropsReadLog* m_outer;
};

}  // namespace lpt
