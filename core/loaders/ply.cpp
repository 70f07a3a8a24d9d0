// Stanford PLY reader (ascii 1.0, binary_little_endian 1.0, binary_big_endian 1.0), written here
// because the format is small and the libraries around it do not say which header line is bad.
// Reads element "vertex" (x y z, optional nx ny nz, optional u v | s t | texture_u texture_v |
// texture_s texture_t, any scalar type) and element "face" (list property vertex_indices or
// vertex_index with integer types); every other element and property is skipped by its declared
// type, so files with colours, tristrips or custom data still load. Polygons are fan-triangulated.
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh.h"
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace lpt {
namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parse_type(const std::string& s, PlyType& t) {
    static const std::pair<const char*, PlyType> names[] = {
        {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (const auto& [name, type] : names)
        if (s == name) return t = type, true;
    return false;
}

size_t type_size(PlyType t) {
    switch (t) {
        case PlyType::Int8:
        case PlyType::UInt8:
            return 1;
        case PlyType::Int16:
        case PlyType::UInt16:
            return 2;
        case PlyType::Int32:
        case PlyType::UInt32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 0;
}

bool is_integer(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    size_t count = 0;
    std::vector<PlyProperty> props;
};

enum class PlyFormat { Ascii, BinaryLE, BinaryBE };

double integer_min(PlyType t) {
    switch (t) {
        case PlyType::Int8:
            return -128.0;
        case PlyType::Int16:
            return -32768.0;
        case PlyType::Int32:
            return -2147483648.0;
        default:
            return 0.0;
    }
}
double integer_max(PlyType t) {
    switch (t) {
        case PlyType::Int8:
            return 127.0;
        case PlyType::UInt8:
            return 255.0;
        case PlyType::Int16:
            return 32767.0;
        case PlyType::UInt16:
            return 65535.0;
        case PlyType::Int32:
            return 2147483647.0;
        default:
            return 4294967295.0;
    }
}

/// Reads scalars from the body; every read is bounds-checked so truncation is an error, not UB.
class PlyBody {
public:
    PlyBody(const std::string& path, const std::string& data, size_t pos, PlyFormat format, int line)
        : m_path(path), m_data(data), m_pos(pos), m_format(format), m_line(line) {}

    /// Names the element being read in error messages.
    void begin_element(const PlyElement& e) { m_element = &e; }
    double read(PlyType t, size_t record) {
        if (m_format == PlyFormat::Ascii) return read_ascii(t, record);
        size_t n = type_size(t);
        if (m_pos + n > m_data.size()) fail("truncated binary data", record);
        unsigned char b[8];
        std::memcpy(b, m_data.data() + m_pos, n);
        m_pos += n;
        static const bool host_le = [] {
            uint16_t one = 1;
            unsigned char c;
            std::memcpy(&c, &one, 1);
            return c == 1;
        }();
        if ((m_format == PlyFormat::BinaryLE) != host_le) std::reverse(b, b + n);
        switch (t) {
            case PlyType::Int8:
                return double(int8_t(b[0]));
            case PlyType::UInt8:
                return double(b[0]);
            case PlyType::Int16: {
                int16_t v;
                std::memcpy(&v, b, 2);
                return v;
            }
            case PlyType::UInt16: {
                uint16_t v;
                std::memcpy(&v, b, 2);
                return v;
            }
            case PlyType::Int32: {
                int32_t v;
                std::memcpy(&v, b, 4);
                return v;
            }
            case PlyType::UInt32: {
                uint32_t v;
                std::memcpy(&v, b, 4);
                return v;
            }
            case PlyType::Float32: {
                float v;
                std::memcpy(&v, b, 4);
                return v;
            }
            case PlyType::Float64: {
                double v;
                std::memcpy(&v, b, 8);
                return v;
            }
        }
        return 0.0;
    }
    size_t remaining() const { return m_data.size() - m_pos; }

    /// Ascii errors carry the line; binary ones the record, which is all a hex dump needs.
    [[noreturn]] void fail(const std::string& what, size_t record) const {
        throw SceneError(m_path, "",
                         what + " in element '" + m_element->name + "' (record " + std::to_string(record) + " of " +
                             std::to_string(m_element->count) + ")",
                         m_format == PlyFormat::Ascii ? m_line : -1);
    }

private:
    double read_ascii(PlyType t, size_t record) {
        while (m_pos < m_data.size() && std::isspace(static_cast<unsigned char>(m_data[m_pos]))) {
            if (m_data[m_pos] == '\n') ++m_line;
            ++m_pos;
        }
        size_t start = m_pos;
        while (m_pos < m_data.size() && !std::isspace(static_cast<unsigned char>(m_data[m_pos]))) ++m_pos;
        if (start == m_pos) fail("truncated ascii data", record);
        std::string tok = m_data.substr(start, m_pos - start);
        char* end = nullptr;
        double v = std::strtod(tok.c_str(), &end);
        if (*end != '\0' || (is_integer(t) && v != std::floor(v))) fail("bad value '" + tok + "'", record);
        // An integer beyond its declared type (1e59 as a vertex index) is as malformed as a
        // fraction, and later conversions to integers rely on the range.
        if (is_integer(t) && !(v >= integer_min(t) && v <= integer_max(t)))
            fail("value '" + tok + "' outside its integer type's range", record);
        return v;
    }

    const std::string& m_path;
    const std::string& m_data;
    size_t m_pos;
    PlyFormat m_format;
    int m_line;  // file line of the ascii cursor
    const PlyElement* m_element = nullptr;
};

struct PlyHeader {
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
    size_t body_start = 0;
    int lines = 0;
};

PlyHeader parse_header(const std::string& path, const std::string& data) {
    PlyHeader h;
    size_t pos = 0;
    int line_no = 0;
    bool have_format = false;
    auto fail = [&](const std::string& msg) {
        throw SceneError(path, "", "PLY header: " + msg, line_no > 0 ? line_no : -1);
    };
    while (true) {
        if (pos >= data.size()) fail("ends before 'end_header'");
        size_t eol = data.find('\n', pos);
        if (eol == std::string::npos) fail("ends before 'end_header'");
        std::string line = data.substr(pos, eol - pos);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        pos = eol + 1;
        ++line_no;
        std::istringstream ss(line);
        std::string kw;
        ss >> kw;
        if (line_no == 1) {
            if (kw != "ply") fail("file does not start with 'ply'");
            continue;
        }
        if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
        if (kw == "end_header") break;
        if (kw == "format") {
            std::string fmt, version;
            ss >> fmt >> version;
            if (fmt == "ascii") h.format = PlyFormat::Ascii;
            else if (fmt == "binary_little_endian") h.format = PlyFormat::BinaryLE;
            else if (fmt == "binary_big_endian") h.format = PlyFormat::BinaryBE;
            else fail("unknown format '" + fmt + "'");
            if (version != "1.0") fail("unsupported format version '" + version + "'");
            have_format = true;
        } else if (kw == "element") {
            PlyElement e;
            long long count = -1;
            if (!(ss >> e.name >> count) || count < 0) fail("bad element line '" + line + "'");
            e.count = size_t(count);
            h.elements.push_back(e);
        } else if (kw == "property") {
            if (h.elements.empty()) fail("property before any element");
            PlyProperty p;
            std::string t1;
            ss >> t1;
            if (t1 == "list") {
                std::string ct, it;
                p.is_list = true;
                if (!(ss >> ct >> it >> p.name)) fail("bad list property line '" + line + "'");
                if (!parse_type(ct, p.count_type) || !is_integer(p.count_type))
                    fail("unsupported list count type '" + ct + "'");
                if (!parse_type(it, p.type)) fail("unsupported property type '" + it + "'");
            } else {
                if (!parse_type(t1, p.type)) fail("unsupported property type '" + t1 + "'");
                if (!(ss >> p.name)) fail("property without a name");
            }
            h.elements.back().props.push_back(p);
        } else {
            fail("unknown keyword '" + kw + "'");
        }
    }
    if (!have_format) fail("no 'format' line");
    h.body_start = pos;
    h.lines = line_no;
    return h;
}

int find_prop(const PlyElement& e, const char* name) {
    for (size_t i = 0; i < e.props.size(); ++i)
        if (e.props[i].name == name) return int(i);
    return -1;
}

/// The vertex element: positions, and normals and uvs where all their properties are present.
void read_vertices(const std::string& path, const PlyElement& e, PlyBody& body, size_t reserve, TriangleMesh& mesh) {
    int ix = find_prop(e, "x"), iy = find_prop(e, "y"), iz = find_prop(e, "z");
    if (ix < 0 || iy < 0 || iz < 0) throw SceneError(path, "", "element 'vertex' lacks one of the properties x, y, z");
    int in[3] = {find_prop(e, "nx"), find_prop(e, "ny"), find_prop(e, "nz")};
    bool has_n = in[0] >= 0 && in[1] >= 0 && in[2] >= 0;
    int iu = -1, iv = -1;
    const std::pair<const char*, const char*> uv_names[] = {
        {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
    for (auto [u, v] : uv_names)
        if (iu < 0 && find_prop(e, u) >= 0 && find_prop(e, v) >= 0) iu = find_prop(e, u), iv = find_prop(e, v);
    for (int i : {ix, iy, iz, in[0], in[1], in[2], iu, iv})
        if (i >= 0 && e.props[size_t(i)].is_list)
            throw SceneError(path, "", "vertex property '" + e.props[size_t(i)].name + "' is a list");
    std::vector<double> values(e.props.size());
    mesh.positions.reserve(reserve);
    for (size_t r = 0; r < e.count; ++r) {
        for (size_t k = 0; k < e.props.size(); ++k) {
            const PlyProperty& p = e.props[k];
            if (!p.is_list) {
                values[k] = body.read(p.type, r);
                continue;
            }
            double n = body.read(p.count_type, r);
            for (double j = 0; j < n; ++j) body.read(p.type, r);
        }
        mesh.positions.emplace_back(float(values[ix]), float(values[iy]), float(values[iz]));
        if (has_n) mesh.normals.emplace_back(float(values[in[0]]), float(values[in[1]]), float(values[in[2]]));
        if (iu >= 0) mesh.uvs.emplace_back(float(values[iu]), float(values[iv]));
    }
}

/// The face element: each polygon of its index list fan-triangulated.
void read_faces(const std::string& path, const PlyElement& e, PlyBody& body, size_t reserve, TriangleMesh& mesh) {
    int il = find_prop(e, "vertex_indices");
    if (il < 0) il = find_prop(e, "vertex_index");
    if (il < 0 || !e.props[size_t(il)].is_list)
        throw SceneError(path, "", "element 'face' has no list property vertex_indices or vertex_index");
    if (!is_integer(e.props[size_t(il)].type))
        throw SceneError(path, "", "face property '" + e.props[size_t(il)].name + "' has a non-integer type");
    mesh.indices.reserve(3 * reserve);
    std::vector<uint32_t> poly;
    for (size_t r = 0; r < e.count; ++r) {
        for (size_t k = 0; k < e.props.size(); ++k) {
            const PlyProperty& p = e.props[k];
            if (!p.is_list) {
                body.read(p.type, r);
                continue;
            }
            double n = body.read(p.count_type, r);
            if (int(k) != il) {
                for (double j = 0; j < n; ++j) body.read(p.type, r);
                continue;
            }
            if (n < 3) body.fail("a face with " + std::to_string(long(n)) + " vertices (needs 3)", r);
            poly.clear();
            for (double j = 0; j < n; ++j) {
                double idx = body.read(p.type, r);
                if (idx < 0 || idx > 4294967295.0)
                    body.fail("vertex index " + std::to_string(static_cast<long long>(idx)) +
                                  " outside the 32-bit unsigned range",
                              r);
                poly.push_back(uint32_t(idx));
            }
            for (size_t j = 1; j + 1 < poly.size(); ++j)
                mesh.indices.insert(mesh.indices.end(), {poly[0], poly[j], poly[j + 1]});
        }
    }
}

void skip_element(const PlyElement& e, PlyBody& body) {
    for (size_t r = 0; r < e.count; ++r)
        for (const PlyProperty& p : e.props) {
            double n = p.is_list ? body.read(p.count_type, r) : 1.0;
            for (double j = 0; j < n; ++j) body.read(p.type, r);
        }
}

}  // namespace

TriangleMesh load_ply(const std::string& path) {
    const std::string data = read_file(path);
    const PlyHeader header = parse_header(path, data);
    PlyBody body(path, data, header.body_start, header.format, header.lines + 1);

    TriangleMesh mesh;
    bool have_vertex = false, have_face = false;
    for (const PlyElement& e : header.elements) {
        // Cap reservations by the bytes left so a bogus count cannot exhaust memory up front.
        const size_t reserve = std::min(e.count, body.remaining() / 2);
        // Records without properties hold no bytes: looping over a claimed count of 10^14 of
        // them would hang (found by fuzzing, tests/fuzz/corpus/ply).
        if (e.props.empty()) {
            if (e.name == "vertex" || e.name == "face")
                throw SceneError(path, "element '" + e.name + "'", "has no properties");
            continue;
        }
        body.begin_element(e);
        if (e.name == "vertex" && !have_vertex) {
            have_vertex = true;
            read_vertices(path, e, body, reserve, mesh);
        } else if (e.name == "face" && !have_face) {
            have_face = true;
            read_faces(path, e, body, reserve, mesh);
        } else {
            skip_element(e, body);
        }
    }
    if (!have_vertex) throw SceneError(path, "", "no element 'vertex'");
    if (!have_face) throw SceneError(path, "", "no element 'face' (point clouds are not meshes)");
    validate_mesh(mesh, path, "");
    return mesh;
}

}  // namespace lpt
