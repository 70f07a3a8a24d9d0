// Internals of the Mitsuba 3 XML loader, shared by mitsuba_xml.cpp (scene structure: plugins,
// ids, shapes), mitsuba_xml_sensor.cpp (sensor, film, sampler, integrator) and
// mitsuba_xml_props.cpp (parameter substitution, property values, transforms). Not part of the
// public API.
#pragma once
#include "core/error.h"
#include "core/props.h"
#include "core/transform.h"
#include <pugixml.hpp>
#include <initializer_list>
#include <map>
#include <string>
#include <vector>

namespace lpt::mitsuba_xml {

/// The XML text and its path; turns pugixml's byte offsets into line numbers for errors.
class Source {
public:
    Source(std::string path, std::string text);
    const std::string& path() const { return m_path; }
    const std::string& text() const { return m_text; }
    int line_of_offset(ptrdiff_t offset) const;
    int line(const pugi::xml_node& n) const { return line_of_offset(n.offset_debug()); }
    [[noreturn]] void fail(const pugi::xml_node& n, const std::string& field, const std::string& msg) const {
        throw SceneError(m_path, field, msg, line(n));
    }
    [[noreturn]] void fail_at(int line, const std::string& field, const std::string& msg) const {
        throw SceneError(m_path, field, msg, line);
    }

private:
    std::string m_path, m_text;
    std::vector<size_t> m_line_starts;
};

/// Rejects attributes other than `allowed` (Mitsuba does too; it catches typos like `vlaue`).
void check_attributes(const Source& src, const pugi::xml_node& n, std::initializer_list<const char*> allowed);
/// Required attribute; error if missing.
std::string required_attribute(const Source& src, const pugi::xml_node& n, const char* name);

/// Collects the top-level <default name value> into `params` (entries already there, from the
/// caller's defines, win), then replaces `$name` in every other attribute of the document.
void substitute_parameters(const Source& src, pugi::xml_node scene, std::map<std::string, std::string> params);

enum class ValueKind { Float, Integer, Boolean, String, Rgb, Point, Vector, Transform };

/// One property element (<float name="fov" value="40"/>, <rgb>, <transform>, ...).
struct Value {
    ValueKind kind = ValueKind::Float;
    PropValue value;  ///< Integer is stored as float here; the exact value is in `integer`
    long long integer = 0;
    int line = -1;
};

bool is_property_tag(const std::string& tag);
/// Parses a property element; returns its name (the `name` attribute).
std::string parse_property(const Source& src, const pugi::xml_node& n, Value& out);
/// Numbers separated by commas and/or whitespace; `what` names the value in errors.
std::vector<float> parse_floats(const Source& src, const pugi::xml_node& n, const std::string& what,
                                const std::string& text);
/// A <transform> element: its operations composed in Mitsuba order (each later one left-multiplies).
Transform parse_transform(const Source& src, const pugi::xml_node& n);
const char* kind_name(ValueKind k);

}  // namespace lpt::mitsuba_xml
