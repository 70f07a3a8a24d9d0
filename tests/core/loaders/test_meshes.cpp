// Mesh readers (OBJ, PLY, glTF), analytic shapes and validate_mesh. Inputs are written from the
// test so each case shows the exact bytes it feeds in; bad inputs must fail with a SceneError that
// names the file and the problem, never crash.
#include "core/error.h"
#include "core/mesh.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cstring>
#include <filesystem>
#include <functional>

using namespace lpt;
using lpt::test::write_temp_file;

namespace {

Vec3f corner(const TriangleMesh& m, size_t t, int k) { return m.positions[m.indices[3 * t + size_t(k)]]; }
Vec3f centroid(const TriangleMesh& m, size_t t) { return (corner(m, t, 0) + corner(m, t, 1) + corner(m, t, 2)) / 3.f; }
Vec3f edge_cross(const TriangleMesh& m, size_t t) {
    return (corner(m, t, 1) - corner(m, t, 0)).cross(corner(m, t, 2) - corner(m, t, 0));
}
double surface_area(const TriangleMesh& m) {
    double a = 0;
    for (size_t t = 0; t < m.triangle_count(); ++t) a += 0.5 * double(edge_cross(m, t).norm());
    return a;
}

/// Runs `fn`, expecting a SceneError whose message contains every string in `parts`.
void expect_scene_error(const std::function<void()>& fn, std::initializer_list<std::string> parts) {
    try {
        fn();
        ADD_FAILURE() << "no SceneError thrown";
    } catch (const SceneError& e) {
        for (const std::string& p : parts) EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    }
}

/// Writes `contents` to a temp file `name`, loads it by extension and expects a SceneError.
void expect_load_error(const std::string& name, const std::string& contents, std::initializer_list<std::string> parts) {
    std::string path = write_temp_file(name, contents);
    expect_scene_error([&] { load_mesh_file(path); }, parts);
}

template <typename T>
void append(std::string& s, T v) {
    s.append(reinterpret_cast<const char*>(&v), sizeof v);  // host order; the tests run on x86-64
}

std::string base64(const std::string& in) {
    static const char* tbl = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < in.size(); i += 3) {
        uint32_t n = uint32_t(uint8_t(in[i])) << 16;
        if (i + 1 < in.size()) n |= uint32_t(uint8_t(in[i + 1])) << 8;
        if (i + 2 < in.size()) n |= uint32_t(uint8_t(in[i + 2]));
        out += tbl[(n >> 18) & 63];
        out += tbl[(n >> 12) & 63];
        out += i + 1 < in.size() ? tbl[(n >> 6) & 63] : '=';
        out += i + 2 < in.size() ? tbl[n & 63] : '=';
    }
    return out;
}

const char* kQuad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

}  // namespace

// ---------------------------------------------------------------- OBJ

TEST(ObjLoader, VertexOnlyQuadIsTwoTriangles) {
    TriangleMesh m = load_obj(write_temp_file("quad.obj", std::string(kQuad) + "f 1 2 3 4\n"));
    EXPECT_EQ(m.positions.size(), 4u);
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_TRUE(m.normals.empty());
    EXPECT_TRUE(m.uvs.empty());
    EXPECT_NEAR(surface_area(m), 1.0, 1e-6);
    for (size_t t = 0; t < 2; ++t) EXPECT_GT(edge_cross(m, t).z(), 0.f);  // winding kept
}

TEST(ObjLoader, FullTriplesGiveNormalsAndUvs) {
    TriangleMesh m = load_obj(write_temp_file(
        "vtvn.obj", std::string(kQuad) + "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 2\nf 1/1/1 2/2/1 3/3/1 4/4/1\n"));
    ASSERT_EQ(m.positions.size(), 4u);
    ASSERT_EQ(m.normals.size(), 4u);
    ASSERT_EQ(m.uvs.size(), 4u);
    for (size_t i = 0; i < 4; ++i) {
        EXPECT_TRUE(m.normals[i].isApprox(Vec3f::UnitZ()));  // renormalised
        EXPECT_TRUE(m.uvs[i].isApprox(m.positions[i].head<2>()));
    }
}

TEST(ObjLoader, VertexNormalWithoutTexcoord) {
    TriangleMesh m = load_obj(write_temp_file("vvn.obj", std::string(kQuad) + "vn 0 0 1\nf 1//1 2//1 3//1\n"));
    EXPECT_EQ(m.triangle_count(), 1u);
    EXPECT_EQ(m.normals.size(), 3u);
    EXPECT_TRUE(m.uvs.empty());
}

TEST(ObjLoader, PentagonIsFanTriangulated) {
    std::string obj;
    for (int k = 0; k < 5; ++k)
        obj +=
            "v " + std::to_string(std::cos(2 * kPi * k / 5)) + " " + std::to_string(std::sin(2 * kPi * k / 5)) + " 0\n";
    TriangleMesh m = load_obj(write_temp_file("pentagon.obj", obj + "f 1 2 3 4 5\n"));
    ASSERT_EQ(m.triangle_count(), 3u);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3, 0, 3, 4}));
    EXPECT_NEAR(surface_area(m), 2.5 * std::sin(2 * kPi / 5), 1e-5);  // regular pentagon, circumradius 1
}

TEST(ObjLoader, SharedTriplesAreDeduplicatedAndShapesMerged) {
    // Two objects, merged. Repeated (v, vt) pairs share a vertex; v 1 with vt 2 (written with
    // relative indices) is a new vertex at the same position.
    TriangleMesh m = load_obj(write_temp_file(
        "dedup.obj",
        std::string(kQuad) + "vt 0 0\nvt 1 1\no a\nf 1/1 2/1 3/1\no b\nf 1/1 3/1 4/1\nf -4/-1 -2/1 -1/1\n"));
    EXPECT_EQ(m.triangle_count(), 3u);
    ASSERT_EQ(m.positions.size(), 5u);
    EXPECT_EQ(m.positions[4], m.positions[0]);
    EXPECT_TRUE(m.uvs[4].isApprox(Vec2f(1, 1)));
}

TEST(ObjLoader, FlipVMirrorsTextureV) {
    std::string obj = std::string(kQuad) + "vt 0.25 0.75\nf 1/1 2/1 3/1\n";
    EXPECT_FLOAT_EQ(load_obj(write_temp_file("flip.obj", obj), false).uvs[0].y(), 0.75f);
    EXPECT_FLOAT_EQ(load_obj(write_temp_file("flip.obj", obj), true).uvs[0].y(), 0.25f);
}

TEST(ObjLoader, MissingFileIsError) {
    expect_scene_error([] { load_obj("/nonexistent/dir/missing.obj"); }, {"missing.obj", "cannot open file"});
}

TEST(ObjLoader, NanVertexIsError) {
    expect_load_error("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
                      {"nan.obj:2", "'nan' is not a finite number"});
}

TEST(ObjLoader, FaceIndexOutOfRangeIsError) {
    expect_load_error("range.obj", std::string(kQuad) + "f 1 2 3\nf 1 2 5\n",
                      {"range.obj:6", "vertex index 5 outside 1..4"});
    // Quads would go through tinyobjloader's own triangulation path, which skipped such faces.
    expect_load_error("range_quad.obj", std::string(kQuad) + "f 1 2 3 9\n", {"range_quad.obj:5", "vertex index 9"});
    expect_load_error("range_vn.obj", std::string(kQuad) + "vn 0 0 1\nf 1//1 2//2 3//1\n",
                      {"range_vn.obj:6", "normal index 2 outside 1..1"});
}

TEST(ObjLoader, ZeroAndNegativeIndicesAreErrors) {
    expect_load_error("zero.obj", std::string(kQuad) + "f 0 1 2\n", {"zero.obj:5", "zero value"});
    // A relative index reaching before vertex 1.
    expect_load_error("negative.obj", std::string(kQuad) + "f -5 1 2\n", {"negative.obj:5", "vertex index"});
    expect_load_error("twovert.obj", std::string(kQuad) + "f 1 2\n", {"twovert.obj:5", "face has 2 vertices"});
}

TEST(ObjLoader, ZeroAreaTriangleIsError) {
    expect_load_error("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 4\nf 1 2 3\n",
                      {"flat.obj", "triangle 1", "zero area"});
}

TEST(ObjLoader, SharedMitsubaScenes) {
    std::string shared = lpt::test::shared_dir();
    std::string quads = shared + "/scenes/cbox/meshes/cbox_floor.obj";        // f v v v v
    std::string triples = shared + "/scenes/veach-bidir/models/Mesh000.obj";  // f v/vt/vn
    if (shared.empty() || !std::filesystem::exists(quads) || !std::filesystem::exists(triples))
        GTEST_SKIP() << "../shared cbox / veach-bidir scenes not present";
    EXPECT_GE(load_obj(quads, true).triangle_count(), 2u);
    TriangleMesh m = load_obj(triples, true);
    EXPECT_GT(m.triangle_count(), 0u);
    EXPECT_EQ(m.normals.size(), m.positions.size());
    EXPECT_EQ(m.uvs.size(), m.positions.size());
}

// ---------------------------------------------------------------- PLY

TEST(PlyLoader, AsciiWithNormalsAndST) {
    std::string ply =
        "ply\nformat ascii 1.0\ncomment written by a test\nobj_info nothing\nelement vertex 4\n"
        "property double x\nproperty double y\nproperty double z\nproperty float nx\nproperty float ny\n"
        "property float nz\nproperty float s\nproperty float t\n"
        "element face 1\nproperty list int uint vertex_index\nend_header\n"
        "0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n";
    TriangleMesh m = load_ply(write_temp_file("ascii.ply", ply));
    EXPECT_EQ(m.triangle_count(), 2u);
    ASSERT_EQ(m.normals.size(), 4u);
    ASSERT_EQ(m.uvs.size(), 4u);
    EXPECT_TRUE(m.uvs[2].isApprox(Vec2f(1, 1)));
    EXPECT_NEAR(surface_area(m), 1.0, 1e-6);
}

namespace {
/// Binary PLY of the unit quad with properties and elements the reader has to skip.
std::string binary_quad_ply() {
    std::string s =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nproperty uchar red\nproperty list uchar short junk\nproperty float u\nproperty float v\n"
        "element face 1\nproperty uchar flags\nproperty list uchar int vertex_indices\n"
        "element edge 1\nproperty list uchar double data\nproperty short id\nend_header\n";
    const float xy[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (const auto& p : xy) {
        append(s, p[0]), append(s, p[1]), append(s, 0.f);
        append(s, uint8_t(200));
        append(s, uint8_t(2)), append(s, int16_t(-1)), append(s, int16_t(7));
        append(s, p[0]), append(s, p[1]);
    }
    append(s, uint8_t(0));
    append(s, uint8_t(4));
    for (int32_t i : {0, 1, 2, 3}) append(s, i);
    append(s, uint8_t(1)), append(s, 3.0), append(s, int16_t(5));
    return s;
}
}  // namespace

TEST(PlyLoader, BinaryLittleEndianSkipsUnknownProperties) {
    TriangleMesh m = load_ply(write_temp_file("binary.ply", binary_quad_ply()));
    EXPECT_EQ(m.positions.size(), 4u);
    EXPECT_EQ(m.triangle_count(), 2u);
    EXPECT_TRUE(m.normals.empty());
    ASSERT_EQ(m.uvs.size(), 4u);
    EXPECT_TRUE(m.uvs[1].isApprox(Vec2f(1, 0)));
    EXPECT_NEAR(surface_area(m), 1.0, 1e-6);
}

TEST(PlyLoader, BinaryBigEndian) {
    std::string s =
        "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n";
    auto be = [&s](auto v) {
        char b[sizeof v];
        std::memcpy(b, &v, sizeof v);
        for (size_t i = sizeof v; i-- > 0;) s += b[i];
    };
    for (float f : {0.f, 0.f, 0.f, 2.f, 0.f, 0.f, 0.f, 3.f, 0.f}) be(f);
    s += char(3);
    for (uint32_t i : {0u, 1u, 2u}) be(i);
    TriangleMesh m = load_ply(write_temp_file("be.ply", s));
    EXPECT_TRUE(m.positions[1].isApprox(Vec3f(2, 0, 0)));
    EXPECT_NEAR(surface_area(m), 3.0, 1e-6);
}

TEST(PlyLoader, TruncatedBinaryIsError) {
    std::string s = binary_quad_ply();
    expect_load_error("truncated.ply", s.substr(0, s.size() - 15),
                      {"truncated.ply", "truncated binary data", "element 'face'"});
}

TEST(PlyLoader, BadHeaderIsError) {
    expect_load_error("badtype.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float128 x\nend_header\n",
                      {"badtype.ply:4", "unsupported property type 'float128'"});
    expect_load_error("noply.ply", "PLY?\nformat ascii 1.0\nend_header\n",
                      {"noply.ply:1", "does not start with 'ply'"});
    expect_load_error("noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n",
                      {"noend.ply", "ends before 'end_header'"});
    expect_load_error("format.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n",
                      {"format.ply:2", "unknown format"});
}

TEST(PlyLoader, FaceIndexOutOfRangeIsError) {
    expect_load_error("plyrange.ply",
                      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                      "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
                      {"plyrange.ply", "triangle 0 has vertex index 3 >= vertex count 3"});
}

// ---------------------------------------------------------------- glTF

namespace {
/// One triangle (indexed, ushort) under a translated parent node whose child scales by 2.
std::string triangle_gltf() {
    std::string bin;
    for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append(bin, f);
    for (uint16_t i : {0, 1, 2}) append(bin, i);
    bin += std::string(2, '\0');
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"translation": [10, 20, 30], "children": [1]}, {"mesh": 0, "scale": [2, 2, 2]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"byteLength": )" +
           std::to_string(bin.size()) + R"(, "uri": "data:application/octet-stream;base64,)" + base64(bin) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})";
}
}  // namespace

TEST(GltfLoader, EmbeddedTriangleWithNodeTransforms) {
    TriangleMesh m = load_gltf(write_temp_file("tri.gltf", triangle_gltf()));
    ASSERT_EQ(m.positions.size(), 3u);
    EXPECT_EQ(m.triangle_count(), 1u);
    EXPECT_TRUE(m.positions[0].isApprox(Vec3f(10, 20, 30)));
    EXPECT_TRUE(m.positions[1].isApprox(Vec3f(12, 20, 30)));
    EXPECT_TRUE(m.positions[2].isApprox(Vec3f(10, 22, 30)));
    EXPECT_GT(edge_cross(m, 0).z(), 0.f);
    EXPECT_EQ(load_mesh_file(write_temp_file("TRI.GLTF", triangle_gltf())).triangle_count(), 1u);  // dispatch
}

TEST(GltfLoader, BinaryGlbWithMirroredNodeAndNormals) {
    // Non-indexed triangle with normals +z under a node mirrored in x: glTF says the winding
    // flips with the determinant, so the front face (and geometric normal) must still be +z.
    std::string bin;
    for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append(bin, f);
    for (int k = 0; k < 3; ++k) append(bin, 0.f), append(bin, 0.f), append(bin, 1.f);
    std::string json = R"({"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}],
      "nodes": [{"mesh": 0, "scale": [-1, 1, 1]}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "mode": 4}]}],
      "buffers": [{"byteLength": 72}],
      "bufferViews": [{"buffer": 0, "byteLength": 72, "byteStride": 12}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                    {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"}]})";
    json.resize((json.size() + 3) / 4 * 4, ' ');  // chunks are 4-byte aligned
    std::string glb = "glTF";
    append(glb, uint32_t(2)), append(glb, uint32_t(12 + 8 + json.size() + 8 + bin.size()));
    append(glb, uint32_t(json.size())), glb += "JSON", glb += json;
    append(glb, uint32_t(bin.size())), glb += std::string("BIN\0", 4), glb += bin;
    TriangleMesh m = load_gltf(write_temp_file("mirror.glb", glb));
    ASSERT_EQ(m.triangle_count(), 1u);
    EXPECT_TRUE(m.positions[1].isApprox(Vec3f(-1, 0, 0)));
    ASSERT_EQ(m.normals.size(), 3u);
    EXPECT_TRUE(m.normals[0].isApprox(Vec3f::UnitZ()));
    EXPECT_GT(edge_cross(m, 0).z(), 0.f);
}

TEST(GltfLoader, AccessorPastBufferIsError) {
    std::string g = triangle_gltf();
    g.replace(g.find("\"count\": 3, \"type\": \"SCALAR\""), 10, "\"count\": 9");
    expect_load_error("overrun.gltf", g, {"overrun.gltf", "reads past the end"});
}

TEST(GltfLoader, MissingFileAndBadJsonAreErrors) {
    expect_scene_error([] { load_gltf("/nonexistent/missing.glb"); }, {"missing.glb", "cannot open file"});
    expect_load_error("broken.gltf", "{\"asset\": ", {"broken.gltf", "cannot parse glTF"});
}

// ---------------------------------------------------------------- analytic shapes

TEST(AnalyticShapes, RectangleAreaAndNormal) {
    TriangleMesh m = make_rectangle();
    EXPECT_NEAR(surface_area(m), 4.0, 1e-6);
    for (size_t t = 0; t < m.triangle_count(); ++t) EXPECT_GT(edge_cross(m, t).z(), 0.f);
    for (const Vec3f& n : m.normals) EXPECT_EQ(n, Vec3f::UnitZ());
    validate_mesh(m, "rectangle", "");
}

TEST(AnalyticShapes, CubeAreaAndOutwardNormals) {
    TriangleMesh m = make_cube();
    EXPECT_EQ(m.positions.size(), 24u);
    EXPECT_EQ(m.triangle_count(), 12u);
    EXPECT_NEAR(surface_area(m), 24.0, 1e-5);
    for (size_t t = 0; t < m.triangle_count(); ++t) {
        Vec3f ng = edge_cross(m, t).normalized();
        EXPECT_GT(ng.dot(centroid(m, t)), 0.f) << "triangle " << t;
        EXPECT_TRUE(ng.isApprox(m.normals[m.indices[3 * t]])) << "triangle " << t;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(std::abs(corner(m, t, k).dot(ng)), 1.f, 1e-6f);  // on the face
    }
    validate_mesh(m, "cube", "");
}

TEST(AnalyticShapes, SphereAreaAndOutwardNormals) {
    TriangleMesh m = make_sphere();
    EXPECT_NEAR(surface_area(m), 4 * kPi, 0.005 * 4 * kPi);
    for (size_t t = 0; t < m.triangle_count(); ++t) EXPECT_GT(edge_cross(m, t).dot(centroid(m, t)), 0.f) << t;
    for (size_t i = 0; i < m.positions.size(); ++i) {
        EXPECT_NEAR(m.positions[i].norm(), 1.f, 1e-6f);
        EXPECT_TRUE(m.normals[i].isApprox(m.positions[i]));
        EXPECT_TRUE((m.uvs[i].array() >= 0.f).all() && (m.uvs[i].array() <= 1.f).all());
    }
    TriangleMesh copy = m;
    validate_mesh(copy, "sphere", "");  // strict: no zero-area triangles at the poles
    EXPECT_EQ(copy.triangle_count(), m.triangle_count());
    EXPECT_EQ(m.triangle_count(), size_t(2 * 128 * (64 - 1)));
    TriangleMesh coarse = make_sphere(2, 3);  // nothing but pole triangles
    EXPECT_EQ(coarse.triangle_count(), 6u);
    validate_mesh(coarse, "sphere", "");
    EXPECT_THROW(make_sphere(1, 8), std::invalid_argument);
}

// ---------------------------------------------------------------- validation and transform

namespace {
TriangleMesh two_triangles() {
    TriangleMesh m;
    m.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(2, 0, 0)};
    m.indices = {0, 1, 2, 0, 1, 3};  // the second is collinear
    return m;
}
}  // namespace

TEST(MeshValidation, ZeroAreaFailsUnlessDropped) {
    TriangleMesh m = two_triangles();
    expect_scene_error([&] { validate_mesh(m, "mesh.obj", "shapes/0"); },
                       {"mesh.obj: field 'shapes/0'", "triangle 1 (vertices 0, 1, 3) has zero area"});
    validate_mesh(m, "mesh.obj", "", true);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));
    TriangleMesh flat = two_triangles();
    flat.indices = {0, 1, 3};
    expect_scene_error([&] { validate_mesh(flat, "flat.obj", "", true); }, {"flat.obj", "no triangles left"});
}

TEST(MeshValidation, IndexOutOfRangeNamesTriangle) {
    TriangleMesh m = two_triangles();
    m.indices = {0, 1, 2, 0, 7, 2};
    expect_scene_error([&] { validate_mesh(m, "m.ply", ""); },
                       {"m.ply", "triangle 1 has vertex index 7 >= vertex count 4"});
    m.indices = {0, 1};
    expect_scene_error([&] { validate_mesh(m, "m.ply", ""); }, {"not a multiple of 3"});
}

TEST(MeshValidation, NonFiniteAndMismatchedAttributes) {
    TriangleMesh m = two_triangles();
    m.indices = {0, 1, 2};
    auto fails_with = [&m](const std::string& msg) { expect_scene_error([&] { validate_mesh(m, "m", ""); }, {msg}); };
    m.positions[2].x() = std::numeric_limits<float>::infinity();
    fails_with("vertex 2 has non-finite position");
    m.positions[2].x() = 0.f;
    m.normals.assign(3, Vec3f::UnitZ());
    fails_with("3 normals but 4 positions");
    m.normals.assign(4, Vec3f::UnitZ());
    m.normals[1] = Vec3f(NAN, 0, 0);
    fails_with("vertex 1 has non-finite normal");
    m.normals[1] = Vec3f::Zero();
    fails_with("vertex 1 has a zero-length normal");
    m.normals[1] = Vec3f(0, 0, 3);
    validate_mesh(m, "m", "");
    EXPECT_TRUE(m.normals[1].isApprox(Vec3f::UnitZ()));  // renormalised in place
    m.uvs.assign(4, Vec2f(NAN, 0));
    fails_with("vertex 0 has a non-finite uv");
    m = TriangleMesh();
    fails_with("no triangles");
}

TEST(MeshValidation, UnknownExtensionAndMissingFiles) {
    expect_scene_error([] { load_mesh_file("model.stl"); }, {"model.stl", "unknown mesh file extension '.stl'"});
    expect_scene_error([] { load_mesh_file("/nonexistent/a.ply"); }, {"a.ply", "cannot open file"});
    expect_scene_error([] { load_mesh_file("/nonexistent/b.OBJ"); }, {"b.OBJ", "cannot open file"});
}

TEST(TriangleMesh, MirrorTransformKeepsGeometricNormalWithShadingNormal) {
    // A pure mirror, and a mirror mixed with non-uniform scale and rotation (det < 0 both).
    for (const Transform& xf : {Transform::scale(Vec3f(-1, 1, 1)),
                                Transform::scale(Vec3f(2, -3, 4)) * Transform::rotate(Vec3f(1, 1, 0), 30.f)}) {
        TriangleMesh m = make_cube();
        m.transform(xf);
        for (size_t t = 0; t < m.triangle_count(); ++t) {
            Vec3f ng = edge_cross(m, t).normalized();
            EXPECT_GT(ng.dot(m.normals[m.indices[3 * t]]), 0.99f) << "triangle " << t;
            EXPECT_GT(ng.dot(centroid(m, t) - xf.point(Vec3f::Zero())), 0.f) << "still outward, triangle " << t;
        }
        for (const Vec3f& n : m.normals) EXPECT_NEAR(n.norm(), 1.f, 1e-6f);
    }
}
