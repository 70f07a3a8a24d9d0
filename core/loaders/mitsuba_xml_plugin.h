// One Mitsuba 3 XML plugin element (<bsdf>, <shape>, <emitter>, ...) read for the loader: its
// properties parsed, typed access where a property of the wrong kind is an error at its line,
// Mitsuba's rule that a plugin rejects properties it never reads, and errors of the plugin
// factories (make_bsdf, make_shape, ...) moved back to the element's XML line.
#pragma once
#include "core/loaders/mitsuba_xml_detail.h"
#include "core/props.h"
#include <initializer_list>
#include <map>
#include <string>
#include <vector>

namespace lpt::mitsuba_xml {

/// A plugin element (<bsdf>, <shape>, ...) with its properties parsed and its nested objects and
/// <ref>s kept in document order.
struct Plugin {
    std::string tag, type, id, where;  ///< where: "shape 'floor'", for error fields
    int line = -1;
    std::map<std::string, Value> values;
    std::vector<pugi::xml_node> children;
    const Value* find(const std::string& name) const {
        auto it = values.find(name);
        return it == values.end() ? nullptr : &it->second;
    }
};

/// The error `e` (thrown by a plugin factory for this file) again, with the XML line added.
[[noreturn]] inline void rethrow_at(const Source& src, const SceneError& e, int line) {
    std::string what = e.what();
    std::string prefix = e.file() + (e.field().empty() ? "" : ": field '" + e.field() + "'") + ": ";
    bool ours = e.file() == src.path() && what.rfind(prefix, 0) == 0;
    throw SceneError(src.path(), e.field(), ours ? what.substr(prefix.size()) : what, line);
}

class PluginReader {
protected:
    explicit PluginReader(const Source& source) : src(source) {}
    const Source& src;

    Plugin read_plugin(const pugi::xml_node& n, const std::string& what) {
        check_attributes(src, n, {"type", "id", "name"});
        Plugin p;
        p.tag = n.name();
        p.type = required_attribute(src, n, "type");
        p.id = n.attribute("id").value();
        p.line = src.line(n);
        p.where = p.id.empty() ? what : what + " '" + p.id + "'";
        for (pugi::xml_node c : n.children()) {
            if (c.type() != pugi::node_element) continue;
            if (!is_property_tag(c.name())) {
                p.children.push_back(c);
                continue;
            }
            Value v;
            std::string name = parse_property(src, c, v);
            if (const Value* old = p.find(name))
                src.fail(c, p.where + "." + name,
                         "property '" + name + "' is given twice (first at line " + std::to_string(old->line) + ")");
            p.values[name] = v;
        }
        return p;
    }

    // Typed property access; a property of the wrong kind is an error at its line.
    const Value* typed(const Plugin& p, const std::string& name, std::initializer_list<ValueKind> kinds,
                       const char* expected) const {
        const Value* v = p.find(name);
        if (!v) return nullptr;
        for (ValueKind k : kinds)
            if (v->kind == k) return v;
        src.fail_at(v->line, p.where + "." + name,
                    std::string("expected <") + expected + ">, got <" + kind_name(v->kind) + ">");
    }
    float get_float(const Plugin& p, const std::string& name, float def) const {
        const Value* v = typed(p, name, {ValueKind::Float, ValueKind::Integer}, "float");
        return v ? std::get<float>(v->value) : def;
    }
    long long get_int(const Plugin& p, const std::string& name, long long def) const {
        const Value* v = typed(p, name, {ValueKind::Integer}, "integer");
        return v ? v->integer : def;
    }
    bool get_bool(const Plugin& p, const std::string& name, bool def) const {
        const Value* v = typed(p, name, {ValueKind::Boolean}, "boolean");
        return v ? std::get<bool>(v->value) : def;
    }
    std::string get_string(const Plugin& p, const std::string& name, const std::string& def) const {
        const Value* v = typed(p, name, {ValueKind::String}, "string");
        return v ? std::get<std::string>(v->value) : def;
    }
    Transform get_transform(const Plugin& p, const std::string& name) const {
        const Value* v = typed(p, name, {ValueKind::Transform}, "transform");
        return v ? std::get<Transform>(v->value) : Transform();
    }
    Vec3f get_point(const Plugin& p, const std::string& name, const Vec3f& def) const {
        const Value* v = typed(p, name, {ValueKind::Point, ValueKind::Vector}, "point");
        return v ? Vec3f(std::get<Eigen::Array3f>(v->value).matrix()) : def;
    }
    [[noreturn]] void fail_value(const Plugin& p, const std::string& name, const std::string& msg) const {
        const Value* v = p.find(name);
        src.fail_at(v ? v->line : p.line, p.where + "." + name, msg);
    }
    /// Mitsuba rejects properties a plugin never reads; so do we, so typos and unsupported
    /// features (e.g. focal_length) surface instead of rendering something else.
    void allow_only(const Plugin& p, std::initializer_list<const char*> names) const {
        for (const auto& [k, v] : p.values) {
            bool ok = false;
            for (const char* n : names) ok = ok || k == n;
            if (ok) continue;
            std::string known;
            for (const char* n : names) known += (known.empty() ? "" : ", ") + std::string(n);
            src.fail_at(v.line, p.where + "." + k,
                        "<" + p.tag + " type=\"" + p.type + "\"> does not support property '" + k + "'" +
                            (known.empty() ? "" : " (supported: " + known + ")"));
        }
    }
    [[noreturn]] void unknown_plugin(const Plugin& p, const std::string& known) const {
        src.fail_at(p.line, p.where + ".type", "unknown " + p.tag + " plugin '" + p.type + "' (known: " + known + ")");
    }
    [[noreturn]] void unexpected_child(const Plugin& p, const pugi::xml_node& c) const {
        src.fail(c, p.where,
                 "unexpected <" + std::string(c.name()) + "> inside <" + p.tag + " type=\"" + p.type + "\">");
    }
    /// A <texture> where only BSDFs take one (shapes, emitters).
    [[noreturn]] void fail_texture(const Plugin& p, const pugi::xml_node& n) const {
        std::string name = n.attribute("name").value();
        src.fail(n, p.where + "." + name,
                 "textured '" + name + "' on <" + p.tag + " type=\"" + p.type +
                     "\"> is not supported yet (bitmap textures work as BSDF parameters)");
    }
    /// The line of the property an error names (`<where>.<name>`), else the plugin's.
    int line_of(const Plugin& p, const std::string& field) const {
        const std::string prefix = p.where + ".";
        if (field.rfind(prefix, 0) != 0) return p.line;
        const Value* v = p.find(field.substr(prefix.size()));
        return v ? v->line : p.line;
    }
};

}  // namespace lpt::mitsuba_xml
