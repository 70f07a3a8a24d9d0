// glTF 2.0 reader (.gltf with embedded or external buffers, .glb) on tinygltf, Debian's shared
// build: no TINYGLTF_IMPLEMENTATION and none of its TINYGLTF_NO_* macros, which would change the
// TinyGLTF class layout against the compiled library.
// The default scene (else scene 0, else every root node) is walked with node matrices / TRS
// applied; every primitive of mode TRIANGLES (or unset), TRIANGLE_STRIP or TRIANGLE_FAN becomes
// triangles of one merged mesh. Attributes: POSITION, NORMAL, TEXCOORD_0; materials, skins and
// morph targets are ignored, and images are not decoded.
#include "core/error.h"
#include "core/mesh.h"
#include <tiny_gltf.h>
#include <algorithm>
#include <cstring>
#include <fstream>

namespace lpt {
namespace {

/// A bounds-checked window onto one accessor's bytes.
struct AccessorView {
    const unsigned char* base = nullptr;
    size_t stride = 0, count = 0;
    int component_type = 0, components = 0;
    bool normalized = false;

    double get(size_t i, int c) const {
        const unsigned char* p = base + i * stride;
        auto load = [&](auto v) {
            std::memcpy(&v, p + size_t(c) * sizeof(v), sizeof(v));
            return v;
        };
        // Normalized integers map to [0, 1] / [-1, 1] (glTF 2.0 section 3.11).
        auto norm = [&](double v, double max) { return normalized ? std::max(v / max, -1.0) : v; };
        switch (component_type) {
            case TINYGLTF_COMPONENT_TYPE_BYTE:
                return norm(load(int8_t()), 127.0);
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                return norm(load(uint8_t()), 255.0);
            case TINYGLTF_COMPONENT_TYPE_SHORT:
                return norm(load(int16_t()), 32767.0);
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
                return norm(load(uint16_t()), 65535.0);
            case TINYGLTF_COMPONENT_TYPE_INT:
                return load(int32_t());
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
                return load(uint32_t());
            case TINYGLTF_COMPONENT_TYPE_FLOAT:
                return load(float());
            case TINYGLTF_COMPONENT_TYPE_DOUBLE:
                return load(double());
        }
        return 0.0;
    }
};

class GltfReader {
public:
    GltfReader(const std::string& path, const tinygltf::Model& model) : m_path(path), m_model(model) {}

    TriangleMesh read() {
        const auto& scenes = m_model.scenes;
        std::vector<int> roots;
        if (!scenes.empty()) {
            int s = m_model.defaultScene >= 0 ? m_model.defaultScene : 0;
            if (size_t(s) >= scenes.size()) fail("default scene " + std::to_string(s) + " does not exist");
            roots = scenes[size_t(s)].nodes;
        } else {
            std::vector<char> is_child(m_model.nodes.size(), 0);
            for (const auto& n : m_model.nodes)
                for (int c : n.children)
                    if (c >= 0 && size_t(c) < is_child.size()) is_child[size_t(c)] = 1;
            for (size_t i = 0; i < is_child.size(); ++i)
                if (!is_child[i]) roots.push_back(int(i));
        }
        m_on_path.assign(m_model.nodes.size(), 0);
        for (int r : roots) visit(r, Eigen::Matrix4d::Identity());
        // As for OBJ: normals only where every primitive has them, zero uvs where missing.
        if (!m_all_normals) m_mesh.normals.clear();
        if (!m_any_uv) m_mesh.uvs.clear();
        validate_mesh(m_mesh, m_path, "");
        return std::move(m_mesh);
    }

private:
    [[noreturn]] void fail(const std::string& msg) const { throw SceneError(m_path, "", msg); }

    void visit(int index, const Eigen::Matrix4d& parent) {
        if (index < 0 || size_t(index) >= m_model.nodes.size())
            fail("node index " + std::to_string(index) + " does not exist");
        // glTF forbids cycles, but a file that has one must not recurse forever.
        if (m_on_path[size_t(index)]) fail("node " + std::to_string(index) + " is its own ancestor");
        const tinygltf::Node& node = m_model.nodes[size_t(index)];
        Eigen::Matrix4d world = parent * local_matrix(node, index);
        if (node.mesh >= 0) {
            if (size_t(node.mesh) >= m_model.meshes.size())
                fail("node " + std::to_string(index) + " has a bad mesh index");
            const auto& prims = m_model.meshes[size_t(node.mesh)].primitives;
            for (size_t p = 0; p < prims.size(); ++p)
                add_primitive(prims[p], "mesh " + std::to_string(node.mesh) + " primitive " + std::to_string(p), world);
        }
        m_on_path[size_t(index)] = 1;
        for (int c : node.children) visit(c, world);
        m_on_path[size_t(index)] = 0;
    }

    Eigen::Matrix4d local_matrix(const tinygltf::Node& n, int index) const {
        if (n.matrix.size() == 16) return Eigen::Map<const Eigen::Matrix4d>(n.matrix.data());  // column-major, as glTF
        if (!n.matrix.empty()) fail("node " + std::to_string(index) + " matrix needs 16 numbers");
        Eigen::Affine3d t = Eigen::Affine3d::Identity();
        if (n.translation.size() == 3)
            t.translate(Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]));
        if (n.rotation.size() == 4)  // glTF stores (x, y, z, w)
            t.rotate(Eigen::Quaterniond(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]).normalized());
        if (n.scale.size() == 3) t.scale(Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]));
        return t.matrix();
    }

    AccessorView view(int index, const std::string& what, int type) const {
        const auto& accessors = m_model.accessors;
        if (index < 0 || size_t(index) >= accessors.size())
            fail(what + ": accessor " + std::to_string(index) + " does not exist");
        const tinygltf::Accessor& a = accessors[size_t(index)];
        if (a.sparse.isSparse) fail(what + ": sparse accessors are not supported");
        if (a.type != type) fail(what + ": accessor " + std::to_string(index) + " has the wrong type");
        if (a.bufferView < 0 || size_t(a.bufferView) >= m_model.bufferViews.size())
            fail(what + ": accessor " + std::to_string(index) + " has no valid bufferView");
        const tinygltf::BufferView& bv = m_model.bufferViews[size_t(a.bufferView)];
        if (bv.buffer < 0 || size_t(bv.buffer) >= m_model.buffers.size())
            fail(what + ": bufferView " + std::to_string(a.bufferView) + " has no valid buffer");
        const std::vector<unsigned char>& data = m_model.buffers[size_t(bv.buffer)].data;
        int stride = a.ByteStride(bv);
        int comp = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        int ncomp = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (stride <= 0 || comp <= 0 || ncomp <= 0)
            fail(what + ": accessor " + std::to_string(index) + " has a bad layout");
        // Everything the accessor reads must lie inside its view, and the view inside the buffer.
        size_t view_end = bv.byteOffset + bv.byteLength;
        if (view_end < bv.byteOffset || view_end > data.size())
            fail(what + ": bufferView " + std::to_string(a.bufferView) + " runs past the end of its buffer");
        size_t elem = size_t(comp) * size_t(ncomp);
        size_t begin = bv.byteOffset + a.byteOffset;
        if (a.count > 0 &&
            (begin > view_end || elem > view_end - begin || a.count - 1 > (view_end - begin - elem) / size_t(stride)))
            fail(what + ": accessor " + std::to_string(index) + " reads past the end of its bufferView");
        return AccessorView{data.data() + begin, size_t(stride), a.count, a.componentType, ncomp, a.normalized};
    }

    void add_primitive(const tinygltf::Primitive& prim, const std::string& what, const Eigen::Matrix4d& world) {
        const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN)
            return;  // points and lines have no area to render
        auto attr = [&](const char* name) {
            auto it = prim.attributes.find(name);
            return it == prim.attributes.end() ? -1 : it->second;
        };
        if (attr("POSITION") < 0) fail(what + " has no POSITION attribute");
        AccessorView pos = view(attr("POSITION"), what + " POSITION", TINYGLTF_TYPE_VEC3);
        TriangleMesh sub;
        for (size_t i = 0; i < pos.count; ++i)
            sub.positions.emplace_back(float(pos.get(i, 0)), float(pos.get(i, 1)), float(pos.get(i, 2)));
        if (attr("NORMAL") >= 0) {
            AccessorView nrm = view(attr("NORMAL"), what + " NORMAL", TINYGLTF_TYPE_VEC3);
            if (nrm.count != pos.count) fail(what + ": NORMAL and POSITION counts differ");
            for (size_t i = 0; i < nrm.count; ++i)
                sub.normals.emplace_back(float(nrm.get(i, 0)), float(nrm.get(i, 1)), float(nrm.get(i, 2)));
        } else {
            m_all_normals = false;
            sub.normals.assign(pos.count, Vec3f::UnitZ());  // placeholder; dropped in read()
        }
        if (attr("TEXCOORD_0") >= 0) {
            AccessorView uv = view(attr("TEXCOORD_0"), what + " TEXCOORD_0", TINYGLTF_TYPE_VEC2);
            if (uv.count != pos.count) fail(what + ": TEXCOORD_0 and POSITION counts differ");
            for (size_t i = 0; i < uv.count; ++i) sub.uvs.emplace_back(float(uv.get(i, 0)), float(uv.get(i, 1)));
            m_any_uv = true;
        } else {
            sub.uvs.assign(pos.count, Vec2f::Zero());
        }

        std::vector<uint32_t> order;
        if (prim.indices >= 0) {
            AccessorView idx = view(prim.indices, what + " indices", TINYGLTF_TYPE_SCALAR);
            if (idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
                fail(what + ": indices must be unsigned byte, short or int");
            idx.normalized = false;
            for (size_t i = 0; i < idx.count; ++i) order.push_back(uint32_t(idx.get(i, 0)));
        } else {
            for (size_t i = 0; i < pos.count; ++i) order.push_back(uint32_t(i));
        }
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (order.size() % 3 != 0)
                fail(what + ": " + std::to_string(order.size()) + " indices is not a multiple of 3");
            sub.indices = std::move(order);
        } else {
            // Strips and fans per the glTF spec (odd strip triangles swap to keep the winding);
            // strips stitch with repeated indices, and those zero-area joins are not triangles.
            for (size_t i = 0; i + 2 < order.size(); ++i) {
                uint32_t a, b, c;
                if (mode == TINYGLTF_MODE_TRIANGLE_FAN) a = order[i + 1], b = order[i + 2], c = order[0];
                else if (i % 2 == 0) a = order[i], b = order[i + 1], c = order[i + 2];
                else a = order[i + 1], b = order[i], c = order[i + 2];
                if (a != b && b != c && a != c) sub.indices.insert(sub.indices.end(), {a, b, c});
            }
        }
        for (uint32_t i : sub.indices)
            if (i >= pos.count)
                fail(what + " has index " + std::to_string(i) + " >= vertex count " + std::to_string(pos.count));

        // TriangleMesh::transform also reverses winding for negative-determinant nodes, as glTF asks.
        sub.transform(Transform(world.cast<float>()));
        const uint32_t base = uint32_t(m_mesh.positions.size());
        m_mesh.positions.insert(m_mesh.positions.end(), sub.positions.begin(), sub.positions.end());
        m_mesh.normals.insert(m_mesh.normals.end(), sub.normals.begin(), sub.normals.end());
        m_mesh.uvs.insert(m_mesh.uvs.end(), sub.uvs.begin(), sub.uvs.end());
        for (uint32_t i : sub.indices) m_mesh.indices.push_back(base + i);
    }

    const std::string& m_path;
    const tinygltf::Model& m_model;
    TriangleMesh m_mesh;
    std::vector<char> m_on_path;
    bool m_all_normals = true, m_any_uv = false;
};

/// Meshes need no pixels; skipping decoding also keeps a missing texture from failing the load.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
    return true;
}

std::string trim(std::string s) {
    while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
    return s;
}

}  // namespace

TriangleMesh load_gltf(const std::string& path) {
    char magic[4] = {};
    {
        std::ifstream in(path, std::ios::binary);
        if (!in) throw SceneError(path, "", "cannot open file");
        in.read(magic, 4);
    }
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&skip_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    bool ok = false;
    try {
        // Decide by content, not extension: some tools write .gltf names on binary files.
        ok = std::equal(magic, magic + 4, "glTF") ? loader.LoadBinaryFromFile(&model, &err, &warn, path)
                                                  : loader.LoadASCIIFromFile(&model, &err, &warn, path);
    } catch (const std::exception& e) {
        throw SceneError(path, "", std::string("cannot parse glTF: ") + e.what());
    }
    if (!ok)
        throw SceneError(path, "", "cannot parse glTF: " + (err.empty() ? std::string("unknown error") : trim(err)));
    return GltfReader(path, model).read();
}

}  // namespace lpt
