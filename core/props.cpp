#include "core/props.h"
#include <cmath>

namespace lpt {

void Props::fail(const std::string& key, const std::string& msg) const {
    throw SceneError(file, where.empty() ? key : where + "." + key, msg);
}

namespace {
thread_local PropsReadLog* t_read_log = nullptr;

template <typename T>
const T* find(const Props& p, const std::string& key, const char* what) {
    p.mark_queried(key);
    auto it = p.values.find(key);
    if (it == p.values.end()) return nullptr;
    if (auto* v = std::get_if<T>(&it->second)) return v;
    p.fail(key, std::string("expected ") + what);
}
void check_finite(const Props& p, const std::string& key, float v) {
    if (!std::isfinite(v)) p.fail(key, "value is not finite");
}
}  // namespace

float Props::get_float(const std::string& key, float def) const {
    auto* v = find<float>(*this, key, "a number");
    if (!v) return def;
    check_finite(*this, key, *v);
    return *v;
}
float Props::get_float(const std::string& key) const {
    if (!has(key)) fail(key, "required number is missing");
    return get_float(key, 0.f);
}
bool Props::get_bool(const std::string& key, bool def) const {
    auto* v = find<bool>(*this, key, "a boolean");
    return v ? *v : def;
}
std::string Props::get_string(const std::string& key, const std::string& def) const {
    auto* v = find<std::string>(*this, key, "a string");
    return v ? *v : def;
}
std::string Props::get_string(const std::string& key) const {
    if (!has(key)) fail(key, "required string is missing");
    return get_string(key, "");
}
Eigen::Array3f Props::get_rgb(const std::string& key, const Eigen::Array3f& def) const {
    mark_queried(key);
    auto it = values.find(key);
    if (it == values.end()) return def;
    Eigen::Array3f out;
    if (auto* f = std::get_if<float>(&it->second)) out = Eigen::Array3f::Constant(*f);
    else if (auto* c = std::get_if<Eigen::Array3f>(&it->second)) out = *c;
    else fail(key, "expected an rgb triple or a number");
    for (int i = 0; i < 3; ++i) check_finite(*this, key, out[i]);
    return out;
}
Eigen::Array3f Props::get_rgb(const std::string& key) const {
    if (!has(key)) fail(key, "required rgb value is missing");
    return get_rgb(key, Eigen::Array3f::Zero());
}
Eigen::Array3f Props::get_colour(const std::string& key, const Eigen::Array3f& def) const {
    const Eigen::Array3f c = get_rgb(key, def);
    if ((c < 0.f).any())
        fail(key, "must be >= 0 in every channel, got (" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " +
                      std::to_string(c[2]) + ")");
    return c;
}
Eigen::Array3f Props::get_colour(const std::string& key) const {
    if (!has(key)) fail(key, "required rgb value is missing");
    return get_colour(key, Eigen::Array3f::Zero());
}
Transform Props::get_transform(const std::string& key, const Transform& def) const {
    auto* v = find<Transform>(*this, key, "a transform");
    return v ? *v : def;
}
std::shared_ptr<Props> Props::get_child(const std::string& key) const {
    auto* v = find<std::shared_ptr<Props>>(*this, key, "a nested object");
    return v ? *v : nullptr;
}

void Props::mark_queried(const std::string& key) const {
    if (t_read_log) t_read_log->note(this, key);
}

PropsReadLog::PropsReadLog() : m_outer(t_read_log) { t_read_log = this; }
PropsReadLog::~PropsReadLog() { t_read_log = m_outer; }

void PropsReadLog::require_all_read(const Props& props) const {
    static const std::set<std::string> kNone;
    auto it = m_read.find(&props);
    const std::set<std::string>& read = it == m_read.end() ? kNone : it->second;
    for (const auto& [key, value] : props.values) {
        if (!read.count(key)) {
            std::string reads;
            for (const std::string& k : read) reads += (reads.empty() ? "" : ", ") + k;
            props.fail(key, "'" + props.type + "' has no property '" + key + "' (it reads " +
                                (reads.empty() ? std::string("none") : reads) + ")");
        }
        if (const auto* child = std::get_if<std::shared_ptr<Props>>(&value); child && *child) require_all_read(**child);
    }
}

}  // namespace lpt
