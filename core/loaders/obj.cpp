// Wavefront OBJ reader on tinyobjloader (Debian's shared build, so no TINYOBJLOADER_IMPLEMENTATION).
// All shapes/groups merge into one mesh; each distinct (v, vt, vn) triple becomes one vertex;
// polygons are fan-triangulated here; materials (usemtl/mtllib) are ignored.
//
// tinyobjloader 2.0.0rc10 is lenient in ways that would hide bad input, so we add:
//  - a pre-pass over v/vt/vn lines: it parses "nan", "1,5" or a missing coordinate as 0 with no
//    message, so every coordinate must parse fully (strtod) and be finite;
//  - our own triangulation (triangulate=false): its quad path silently skips faces with an
//    out-of-range index and its ear clipper can drop parts of a polygon; its per-face vertex count
//    is an unsigned char, so the pre-pass rejects faces with more than 255 vertices;
//  - index range checks: an index past the end is only a warning that names the last line of
//    the file, and a relative index reaching before the first vertex resolves to a negative one.
// Its warnings are otherwise ignored: they are about materials or are covered by the checks.
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh.h"
#include <tiny_obj_loader.h>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <unordered_map>

namespace lpt {
namespace {

std::vector<std::string> split_ws(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream ss(line);
    for (std::string tok; ss >> tok;) out.push_back(tok);
    return out;
}

/// Checks the numbers tinyobjloader would accept silently and returns the line of each face
/// with >= 3 vertices, in file order, so later errors can name a face's line.
std::vector<int> prescan(const std::string& path, const std::string& text) {
    std::vector<int> face_lines;
    std::istringstream in(text);
    int line_no = 0;
    for (std::string line; std::getline(in, line);) {
        ++line_no;
        std::vector<std::string> tok = split_ws(line);
        if (tok.empty()) continue;
        const std::string& kw = tok[0];
        if (kw == "v" || kw == "vn" || kw == "vt") {
            size_t need = kw == "vt" ? 1 : 3;
            if (tok.size() < need + 1)
                throw SceneError(path, "", "'" + kw + "' needs " + std::to_string(need) + " coordinates", line_no);
            size_t check = std::min(tok.size() - 1, kw == "vt" ? size_t(2) : size_t(3));
            for (size_t i = 1; i <= check; ++i) {
                const char* s = tok[i].c_str();
                char* end = nullptr;
                errno = 0;
                double x = std::strtod(s, &end);
                if (end == s || *end != '\0' || !std::isfinite(x) || errno == ERANGE)
                    throw SceneError(path, "", "'" + kw + "' coordinate '" + tok[i] + "' is not a finite number",
                                     line_no);
            }
        } else if (kw == "f") {
            size_t n = tok.size() - 1;
            if (n < 3) throw SceneError(path, "", "face has " + std::to_string(n) + " vertices (needs 3)", line_no);
            if (n > 255)
                throw SceneError(path, "", "face has " + std::to_string(n) + " vertices (at most 255 supported)",
                                 line_no);
            face_lines.push_back(line_no);
        }
    }
    return face_lines;
}

/// tinyobjloader messages look like "... line 7.)\n"; pull the number out for SceneError.
int line_in_message(const std::string& msg) {
    for (size_t p = msg.find("line"); p != std::string::npos; p = msg.find("line", p + 4)) {
        size_t d = msg.find_first_not_of(": ", p + 4);
        if (d != std::string::npos && std::isdigit(static_cast<unsigned char>(msg[d])))
            return std::atoi(msg.c_str() + d);
    }
    return -1;
}

std::string trim(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ' || s.back() == '.')) s.pop_back();
    return s;
}

struct CornerKey {
    int v, vt, vn;
    bool operator==(const CornerKey& o) const { return v == o.v && vt == o.vt && vn == o.vn; }
};
struct CornerHash {
    size_t operator()(const CornerKey& k) const {
        uint64_t h = uint64_t(uint32_t(k.v)) * 0x9E3779B97F4A7C15ull;
        h ^= (uint64_t(uint32_t(k.vt)) + 0x7F4A7C15ull + (h << 6) + (h >> 2)) * 0xBF58476D1CE4E5B9ull;
        h ^= (uint64_t(uint32_t(k.vn)) + 0x94D049BBull + (h << 6) + (h >> 2)) * 0x94D049BB133111EBull;
        return size_t(h ^ (h >> 31));
    }
};

}  // namespace

TriangleMesh load_obj(const std::string& path, bool flip_v, bool drop_degenerate) {
    const std::string text = read_file(path);
    const std::vector<int> face_lines = prescan(path, text);

    tinyobj::ObjReaderConfig config;
    config.triangulate = false;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(text, "", config)) {
        const std::string& err = reader.Error();
        throw SceneError(path, "", err.empty() ? "cannot parse OBJ" : trim(err), line_in_message(err));
    }
    const tinyobj::attrib_t& attrib = reader.GetAttrib();
    const long nv = long(attrib.vertices.size() / 3), nt = long(attrib.texcoords.size() / 2),
               nn = long(attrib.normals.size() / 3);

    size_t face_count = 0;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) face_count += shape.mesh.num_face_vertices.size();
    // Line numbers only if our face count agrees with tinyobjloader's, so they cannot mislead.
    const bool lines_known = face_count == face_lines.size();

    TriangleMesh mesh;
    std::unordered_map<CornerKey, uint32_t, CornerHash> vertex_of;
    bool all_have_normals = true, any_uv = false;
    std::vector<uint32_t> poly;
    size_t face_no = 0;
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        size_t offset = 0;
        for (unsigned char fv : shape.mesh.num_face_vertices) {
            const int line = lines_known ? face_lines[face_no] : -1;
            auto bad = [&](const char* what, long idx, long count) {
                throw SceneError(path, "",
                                 "face " + std::to_string(face_no) + " has " + what + " index " +
                                     std::to_string(idx + 1) + " outside 1.." + std::to_string(count),
                                 line);
            };
            poly.clear();
            for (size_t k = 0; k < fv; ++k) {
                const tinyobj::index_t& ix = shape.mesh.indices.at(offset + k);
                if (ix.vertex_index < 0 || ix.vertex_index >= nv) bad("vertex", ix.vertex_index, nv);
                // -1 means "absent"; a relative index that overshoots lands below -1.
                if (ix.texcoord_index < -1 || ix.texcoord_index >= nt) bad("texcoord", ix.texcoord_index, nt);
                if (ix.normal_index < -1 || ix.normal_index >= nn) bad("normal", ix.normal_index, nn);
                CornerKey key{ix.vertex_index, ix.texcoord_index, ix.normal_index};
                auto [it, inserted] = vertex_of.try_emplace(key, uint32_t(mesh.positions.size()));
                if (inserted) {
                    const tinyobj::real_t* p = &attrib.vertices[3 * size_t(key.v)];
                    mesh.positions.emplace_back(float(p[0]), float(p[1]), float(p[2]));
                    Vec3f n = Vec3f::Zero();
                    if (key.vn >= 0) {
                        const tinyobj::real_t* q = &attrib.normals[3 * size_t(key.vn)];
                        n = Vec3f(float(q[0]), float(q[1]), float(q[2]));
                    } else {
                        all_have_normals = false;
                    }
                    mesh.normals.push_back(n);
                    Vec2f uv = Vec2f::Zero();
                    if (key.vt >= 0) {
                        any_uv = true;
                        const tinyobj::real_t* t = &attrib.texcoords[2 * size_t(key.vt)];
                        uv = Vec2f(float(t[0]), flip_v ? 1.f - float(t[1]) : float(t[1]));
                    }
                    mesh.uvs.push_back(uv);
                }
                poly.push_back(it->second);
            }
            for (size_t k = 1; k + 1 < poly.size(); ++k)
                mesh.indices.insert(mesh.indices.end(), {poly[0], poly[k], poly[k + 1]});
            offset += fv;
            ++face_no;
        }
    }
    // Half-specified normals would mix smooth and flat shading on a whim of the exporter; flat
    // (geometric) normals everywhere is the predictable choice. Missing uvs read as (0, 0).
    if (!all_have_normals) mesh.normals.clear();
    if (!any_uv) mesh.uvs.clear();
    validate_mesh(mesh, path, "", drop_degenerate);
    return mesh;
}

}  // namespace lpt
