// Mitsuba 3 XML: line numbers, `$name` parameter substitution, property elements and
// transforms. Scene structure (plugins, ids, shapes) is in mitsuba_xml.cpp.
#include "core/loaders/mitsuba_xml_detail.h"
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <set>

namespace lpt::mitsuba_xml {

Source::Source(std::string path, std::string text) : m_path(std::move(path)), m_text(std::move(text)) {
    m_line_starts.push_back(0);
    for (size_t i = 0; i < m_text.size(); ++i)
        if (m_text[i] == '\n') m_line_starts.push_back(i + 1);
}

int Source::line_of_offset(ptrdiff_t offset) const {
    if (offset < 0) return -1;
    auto it = std::upper_bound(m_line_starts.begin(), m_line_starts.end(), size_t(offset));
    return int(it - m_line_starts.begin());
}

void check_attributes(const Source& src, const pugi::xml_node& n, std::initializer_list<const char*> allowed) {
    for (pugi::xml_attribute a : n.attributes()) {
        bool ok = false;
        for (const char* name : allowed) ok = ok || std::string(a.name()) == name;
        if (!ok) {
            std::string known;
            for (const char* name : allowed) known += (known.empty() ? "" : ", ") + std::string(name);
            src.fail(
                n, "",
                "<" + std::string(n.name()) + ">: unexpected attribute '" + a.name() + "' (allowed: " + known + ")");
        }
    }
}

std::string required_attribute(const Source& src, const pugi::xml_node& n, const char* name) {
    pugi::xml_attribute a = n.attribute(name);
    if (!a) src.fail(n, "", "<" + std::string(n.name()) + ">: missing attribute '" + name + "'");
    return a.value();
}

namespace {

bool is_ident(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

/// `$name` → params[name], taking the longest identifier after `$` (Mitsuba's plain string
/// replace would turn `$resx` into "64x" when only `res` is defined). A `$` not followed by
/// an identifier stays literal.
std::string substitute(const Source& src, const pugi::xml_node& n, const pugi::xml_attribute& a,
                       const std::map<std::string, std::string>& params, std::set<std::string>& used) {
    std::string in = a.value(), out;
    for (size_t i = 0; i < in.size(); ++i) {
        if (in[i] != '$' || i + 1 >= in.size() || !is_ident(in[i + 1])) {
            out += in[i];
            continue;
        }
        size_t j = i + 1;
        while (j < in.size() && is_ident(in[j])) ++j;
        std::string name = in.substr(i + 1, j - i - 1);
        auto it = params.find(name);
        if (it == params.end())
            src.fail(n, a.name(),
                     "undefined parameter '$" + name + "' in <" + n.name() + ">: declare <default name=\"" + name +
                         "\" value=\"...\"/> or pass it as a define");
        used.insert(name);
        out += it->second;
        i = j - 1;
    }
    return out;
}

void substitute_tree(const Source& src, pugi::xml_node n, const std::map<std::string, std::string>& params,
                     std::set<std::string>& used) {
    for (pugi::xml_attribute a : n.attributes())
        if (std::string(a.value()).find('$') != std::string::npos)
            a.set_value(substitute(src, n, a, params, used).c_str());
    for (pugi::xml_node c : n.children())
        if (c.type() == pugi::node_element) substitute_tree(src, c, params, used);
}

float parse_float_token(const Source& src, const pugi::xml_node& n, const std::string& what, const std::string& tok) {
    const char* first = tok.data();
    const char* last = tok.data() + tok.size();
    if (first != last && *first == '+') ++first;  // from_chars rejects a leading '+'
    float v = 0.f;
    auto [ptr, ec] = std::from_chars(first, last, v);
    if (ec != std::errc() || ptr != last || tok.empty() || !std::isfinite(v))
        src.fail(n, what, "'" + tok + "' is not a finite number");
    return v;
}

Vec3f parse_vec3(const Source& src, const pugi::xml_node& n, const std::string& what, const std::string& text) {
    std::vector<float> v = parse_floats(src, n, what, text);
    if (v.size() != 3) src.fail(n, what, "expected 3 numbers, got " + std::to_string(v.size()) + " in '" + text + "'");
    return Vec3f(v[0], v[1], v[2]);
}

/// `value="x, y, z"` if `vec_attr` is present, else x/y/z attributes defaulting to `def`.
Vec3f named_vector(const Source& src, const pugi::xml_node& n, const char* vec_attr, float def, bool allow_broadcast) {
    if (pugi::xml_attribute a = n.attribute(vec_attr)) {
        if (n.attribute("x") || n.attribute("y") || n.attribute("z"))
            src.fail(n, vec_attr, "give either '" + std::string(vec_attr) + "' or x/y/z, not both");
        std::vector<float> v = parse_floats(src, n, vec_attr, a.value());
        if (allow_broadcast && v.size() == 1) return Vec3f::Constant(v[0]);
        if (v.size() != 3)
            src.fail(
                n, vec_attr,
                std::string("expected ") + (allow_broadcast ? "1 or " : "") + "3 numbers, got '" + a.value() + "'");
        return Vec3f(v[0], v[1], v[2]);
    }
    Vec3f out = Vec3f::Constant(def);
    for (int i = 0; i < 3; ++i) {
        const char* axis = i == 0 ? "x" : i == 1 ? "y" : "z";
        if (pugi::xml_attribute a = n.attribute(axis)) out[i] = parse_float_token(src, n, axis, a.value());
    }
    return out;
}

Transform transform_op(const Source& src, const pugi::xml_node& op) {
    const std::string tag = op.name();
    if (tag == "translate") {
        check_attributes(src, op, {"value", "x", "y", "z"});
        return Transform::translate(named_vector(src, op, "value", 0.f, false));
    }
    if (tag == "scale") {
        check_attributes(src, op, {"value", "x", "y", "z"});
        // Unset axes keep their size (a 0 default would flatten the shape).
        return Transform::scale(named_vector(src, op, "value", 1.f, true));
    }
    if (tag == "rotate") {
        check_attributes(src, op, {"axis", "x", "y", "z", "angle"});
        Vec3f axis = named_vector(src, op, "axis", 0.f, false);
        if (axis.norm() == 0.f) src.fail(op, "axis", "rotation axis has zero length");
        float angle = parse_float_token(src, op, "angle", required_attribute(src, op, "angle"));
        return Transform::rotate(axis, angle);
    }
    if (tag == "lookat") {
        check_attributes(src, op, {"origin", "target", "up"});
        Vec3f o = parse_vec3(src, op, "origin", required_attribute(src, op, "origin"));
        Vec3f t = parse_vec3(src, op, "target", required_attribute(src, op, "target"));
        Vec3f up = parse_vec3(src, op, "up", required_attribute(src, op, "up"));
        if ((t - o).norm() == 0.f) src.fail(op, "target", "lookat origin and target coincide");
        try {
            return Transform::look_at(o, t, up);
        } catch (const std::invalid_argument& e) {
            src.fail(op, "up", e.what());
        }
    }
    if (tag == "matrix") {
        check_attributes(src, op, {"value"});
        std::string text = required_attribute(src, op, "value");
        std::vector<float> v = parse_floats(src, op, "value", text);
        Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
        if (v.size() == 16) {
            for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = v[i];
        } else if (v.size() == 9) {  // Mitsuba 3 also takes a 3x3 linear part
            for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = v[i];
        } else {
            src.fail(op, "value", "matrix needs 16 (or 9) numbers, row-major; got " + std::to_string(v.size()));
        }
        return Transform(m);
    }
    src.fail(op, "", "unknown transform operation <" + tag + "> (known: translate, scale, rotate, lookat, matrix)");
}

}  // namespace

void substitute_parameters(const Source& src, pugi::xml_node scene, std::map<std::string, std::string> params) {
    const std::map<std::string, std::string> defines = params;
    std::set<std::string> used;  // declared by a <default> or referenced as $name
    for (pugi::xml_node d : scene.children("default")) {
        check_attributes(src, d, {"name", "value"});
        std::string name = required_attribute(src, d, "name");
        if (name.empty()) src.fail(d, "name", "<default> needs a non-empty name");
        required_attribute(src, d, "value");
        std::string value = substitute(src, d, d.attribute("value"), params, used);
        params.emplace(name, value);  // a define, or an earlier <default> of the same name, wins
        used.insert(name);
    }
    for (pugi::xml_attribute a : scene.attributes())
        if (std::string(a.value()).find('$') != std::string::npos)
            a.set_value(substitute(src, scene, a, params, used).c_str());
    for (pugi::xml_node c : scene.children())
        if (c.type() == pugi::node_element && std::string(c.name()) != "default") substitute_tree(src, c, params, used);
    // A define the scene never mentions changes nothing: most likely a misspelt name (-D sppp=64)
    // or a JSON-style dotted path; say so rather than render with the default.
    for (const auto& [name, value] : defines)
        if (!used.count(name))
            throw SceneError(src.path(), "-D " + name,
                             "the scene has no parameter '" + name + "' (no <default name=\"" + name + "\"> and no $" +
                                 name + " in any attribute)");
}

std::vector<float> parse_floats(const Source& src, const pugi::xml_node& n, const std::string& what,
                                const std::string& text) {
    std::vector<float> out;
    size_t i = 0;
    auto sep = [](char c) { return c == ',' || std::isspace(static_cast<unsigned char>(c)); };
    while (i < text.size()) {
        while (i < text.size() && sep(text[i])) ++i;
        size_t j = i;
        while (j < text.size() && !sep(text[j])) ++j;
        if (j > i) out.push_back(parse_float_token(src, n, what, text.substr(i, j - i)));
        i = j;
    }
    return out;
}

Transform parse_transform(const Source& src, const pugi::xml_node& n) {
    Transform t;
    for (pugi::xml_node op : n.children()) {
        if (op.type() != pugi::node_element) continue;
        t = transform_op(src, op) * t;
    }
    float det = t.m.topLeftCorner<3, 3>().determinant();
    if (!(std::abs(det) > 0.f) || !t.inv.allFinite()) src.fail(n, n.attribute("name").value(), "transform is singular");
    return t;
}

bool is_property_tag(const std::string& tag) {
    static const char* kTags[] = {"float",    "integer", "boolean", "string",   "rgb",
                                  "spectrum", "point",   "vector",  "transform"};
    return std::find_if(std::begin(kTags), std::end(kTags), [&](const char* t) { return tag == t; }) != std::end(kTags);
}

const char* kind_name(ValueKind k) {
    switch (k) {
        case ValueKind::Float:
            return "float";
        case ValueKind::Integer:
            return "integer";
        case ValueKind::Boolean:
            return "boolean";
        case ValueKind::String:
            return "string";
        case ValueKind::Rgb:
            return "rgb";
        case ValueKind::Point:
            return "point";
        case ValueKind::Vector:
            return "vector";
        case ValueKind::Transform:
            return "transform";
    }
    return "?";
}

std::string parse_property(const Source& src, const pugi::xml_node& n, Value& out) {
    const std::string tag = n.name();
    out.line = src.line(n);
    if (tag == "transform") {
        check_attributes(src, n, {"name"});
        std::string name = required_attribute(src, n, "name");
        out.kind = ValueKind::Transform;
        out.value = parse_transform(src, n);
        return name;
    }
    if (tag == "point" || tag == "vector") {
        check_attributes(src, n, {"name", "value", "x", "y", "z"});
        std::string name = required_attribute(src, n, "name");
        out.kind = tag == "point" ? ValueKind::Point : ValueKind::Vector;
        out.value = Eigen::Array3f(named_vector(src, n, "value", 0.f, false).array());
        return name;
    }
    check_attributes(src, n, {"name", "value"});
    std::string name = required_attribute(src, n, "name");
    std::string value = required_attribute(src, n, "value");
    if (tag == "float") {
        out.kind = ValueKind::Float;
        std::vector<float> v = parse_floats(src, n, name, value);
        if (v.size() != 1) src.fail(n, name, "expected one number, got '" + value + "'");
        out.value = v[0];
    } else if (tag == "integer") {
        out.kind = ValueKind::Integer;
        const char* first = value.data();
        const char* last = value.data() + value.size();
        if (first != last && *first == '+') ++first;
        auto [ptr, ec] = std::from_chars(first, last, out.integer);
        if (ec != std::errc() || ptr != last || value.empty() || out.integer > INT32_MAX || out.integer < INT32_MIN)
            src.fail(n, name, "'" + value + "' is not an integer");
        out.value = float(out.integer);
    } else if (tag == "boolean") {
        out.kind = ValueKind::Boolean;
        std::string v = value;
        for (char& c : v) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (v != "true" && v != "false") src.fail(n, name, "expected true or false, got '" + value + "'");
        out.value = v == "true";
    } else if (tag == "string") {
        out.kind = ValueKind::String;
        out.value = value;
    } else if (tag == "rgb" || tag == "spectrum") {
        // A spectrum is accepted only as one uniform value; wavelength:value lists need spectral
        // upsampling that RGB rendering does not have.
        out.kind = ValueKind::Rgb;
        if (tag == "spectrum" && value.find(':') != std::string::npos)
            src.fail(n, name,
                     "<spectrum> with wavelength:value pairs is not supported; use <rgb> or one uniform value");
        std::vector<float> v = parse_floats(src, n, name, value);
        if (v.size() == 1) out.value = Eigen::Array3f::Constant(v[0]);
        else if (v.size() == 3 && tag == "rgb") out.value = Eigen::Array3f(v[0], v[1], v[2]);
        else
            src.fail(
                n, name,
                "<" + tag + "> expects " + (tag == "rgb" ? "\"r, g, b\" or " : "") + "one value, got '" + value + "'");
    } else {
        src.fail(n, name, "<" + tag + "> is not a property element");
    }
    return name;
}

}  // namespace lpt::mitsuba_xml
