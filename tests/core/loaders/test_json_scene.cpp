// JSON scene loader: valid scenes load; every kind of bad input is a SceneError that names the
// file and the field.
#include "core/error.h"
#include "core/props.h"
#include <cmath>
#include "core/scene_loader.h"
#include "test_util.h"
#include <gtest/gtest.h>

using namespace lpt;

namespace {

const char* kCamera =
    R"("camera": {"fov": 40, "width": 16, "height": 12, "to_world": {"lookat": {"origin": [0,0,-3], "target": [0,0,0], "up": [0,1,0]}}})";

std::string scene_json(const std::string& materials, const std::string& shapes, const std::string& extra = "") {
    return std::string("{") + kCamera + R"(, "materials": {)" + materials + R"(}, "shapes": [)" + shapes + "]" + extra +
           "}";
}

/// Loads `json` from a temp file and returns the SceneError message ("" if it loaded).
std::string load_error(const std::string& name, const std::string& json) {
    std::string path = test::write_temp_file(name, json);
    try {
        load_scene(path);
    } catch (const SceneError& e) {
        return e.what();
    }
    return "";
}

const std::string kWhite = R"("white": {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]})";
const std::string kQuad =
    R"({"id": "q", "type": "mesh", "material": "white", "positions": [[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]], "indices": [[0,1,2,3]]})";

}  // namespace

TEST(JsonScene, LoadsCornellBox) {
    Scene s = load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json");
    EXPECT_EQ(s.shapes.size(), 8u);
    ASSERT_EQ(s.emitters.size(), 1u);
    EXPECT_EQ(s.shapes[s.emitters[0].shape].id, "light");
    EXPECT_EQ(s.camera.width, 256);
    // The classic box is ~5.5 units wide after the 0.01 scale; light faces down.
    const Shape& light = s.shapes[s.find_shape("light")];
    EXPECT_NEAR(light.area(), 1.30f * 1.05f, 1e-3f);
    EXPECT_LT(light.sample_position(Eigen::Vector3f(0.5f, 0.5f, 0.5f)).n.y(), -0.99f);
}

TEST(JsonScene, DefinesOverrideValues) {
    std::string path = test::write_temp_file("defines.json", scene_json(kWhite, kQuad));
    Scene s = load_scene(path, {{"integrator.spp", "7"}, {"camera.width", "33"}});
    EXPECT_EQ(s.integrator.spp, 7);
    EXPECT_EQ(s.camera.width, 33);
}

TEST(JsonScene, TransformListComposesInOrder) {
    // scale then translate: later ops left-multiply (Mitsuba order).
    std::string shape =
        R"({"id": "q", "type": "rectangle", "material": "white", "to_world": [{"scale": 2}, {"translate": [0, 0, 5]}]})";
    Scene s = load_scene(test::write_temp_file("xf.json", scene_json(kWhite, shape)));
    EXPECT_NEAR(s.shapes[0].area(), 16.f, 1e-4f);
    EXPECT_NEAR(s.shapes[0].mesh.positions[0].z(), 5.f, 1e-6f);
}

TEST(JsonScene, MissingFileNamesFile) {
    try {
        load_scene("/nonexistent/dir/scene.json");
        FAIL() << "expected SceneError";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/scene.json"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
    }
}

TEST(JsonScene, MalformedJsonReportsPosition) {
    std::string err = load_error("malformed.json", "{\n  \"camera\": {\"fov\": 40,,}\n}");
    EXPECT_NE(err.find("malformed.json"), std::string::npos) << err;
    EXPECT_NE(err.find("line 2"), std::string::npos) << err;
}

// Values the XML loader refuses are refused here too, naming the field: a collapsed camera frame
// (Embree aborted on its zero-direction rays), clip planes that clip every ray, depths out of range.
TEST(JsonScene, DegenerateCameraAndOutOfRangeSettingsNameTheirField) {
    auto with_camera = [](const std::string& camera, const std::string& integrator = "{}") {
        return std::string(R"({"camera": )") + camera + R"(, "integrator": )" + integrator + R"(, "materials": {)" +
               kWhite + "}, \"shapes\": [" + kQuad + "]}";
    };
    const std::vector<std::pair<std::string, std::string>> cases = {
        {with_camera(R"({"to_world": {"scale": 0}})"), "camera.to_world"},
        {with_camera(R"({"to_world": [{"scale": 1e-30}, {"translate": [0, 0, 5]}]})"), "camera.to_world"},
        {with_camera(R"({"near_clip": -1})"), "camera.near_clip"},
        {with_camera(R"({"near_clip": 5, "far_clip": 1})"), "camera.far_clip"},
        {with_camera("{}", R"({"max_depth": -5})"), "integrator.max_depth"},
        {with_camera("{}", R"({"rr_depth": 0})"), "integrator.rr_depth"},
    };
    for (const auto& [json, field] : cases) {
        const std::string err = load_error("degenerate.json", json);
        EXPECT_NE(err.find(field), std::string::npos) << field << ": " << err;
    }
    std::string shape = R"({"id": "q", "type": "rectangle", "material": "white", "to_world": {"scale": [1, 0, 1]}})";
    EXPECT_NE(load_error("flat.json", scene_json(kWhite, shape)).find("shapes[0].to_world"), std::string::npos);
}

TEST(JsonScene, UnknownMaterialTypeNamesField) {
    std::string err = load_error("badmat.json", scene_json(R"("white": {"type": "velvet"})", kQuad));
    EXPECT_NE(err.find("badmat.json"), std::string::npos) << err;
    EXPECT_NE(err.find("materials.white"), std::string::npos) << err;
    EXPECT_NE(err.find("velvet"), std::string::npos) << err;
}

TEST(JsonScene, MalformedNumberNamesField) {
    std::string err =
        load_error("badnum.json", scene_json(R"("white": {"type": "diffuse", "reflectance": [0.5, "x", 0.5]})", kQuad));
    EXPECT_NE(err.find("materials.white.reflectance"), std::string::npos) << err;
    err = load_error("badfov.json", std::string(R"({"camera": {"fov": "wide"}, "materials": {)") + kWhite +
                                        "}, \"shapes\": [" + kQuad + "]}");
    EXPECT_NE(err.find("camera.fov"), std::string::npos) << err;
}

TEST(JsonScene, UnknownMaterialReferenceNamesShape) {
    std::string shape = R"({"id": "q", "type": "rectangle", "material": "whte"})";
    std::string err = load_error("badref.json", scene_json(kWhite, shape));
    EXPECT_NE(err.find("shapes[0].material"), std::string::npos) << err;
    EXPECT_NE(err.find("whte"), std::string::npos) << err;
}

TEST(JsonScene, IndexOutOfRangeNamesPolygon) {
    std::string shape =
        R"({"id": "q", "type": "mesh", "material": "white", "positions": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,3]]})";
    std::string err = load_error("badidx.json", scene_json(kWhite, shape));
    EXPECT_NE(err.find("shapes[0].indices[0]"), std::string::npos) << err;
    EXPECT_NE(err.find("out of range"), std::string::npos) << err;
}

TEST(JsonScene, ZeroAreaTriangleIsAnError) {
    std::string shape =
        R"({"id": "q", "type": "mesh", "material": "white", "positions": [[0,0,0],[1,0,0],[2,0,0]], "indices": [[0,1,2]]})";
    std::string err = load_error("degenerate.json", scene_json(kWhite, shape));
    EXPECT_NE(err.find("degenerate.json"), std::string::npos) << err;
    EXPECT_NE(err.find("shapes[0]"), std::string::npos) << err;
}

TEST(JsonScene, MissingMeshFileNamesBothFiles) {
    std::string shape = R"({"id": "q", "type": "obj", "filename": "meshes/missing.obj", "material": "white"})";
    std::string err = load_error("missingmesh.json", scene_json(kWhite, shape));
    EXPECT_NE(err.find("missingmesh.json"), std::string::npos) << err;
    EXPECT_NE(err.find("shapes[0].filename"), std::string::npos) << err;
    EXPECT_NE(err.find("missing.obj"), std::string::npos) << err;
}

TEST(JsonScene, NanInMeshFileIsAnError) {
    test::write_temp_file("meshes/nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    std::string shape = R"({"id": "q", "type": "obj", "filename": "meshes/nan.obj", "material": "white"})";
    std::string err = load_error("nanmesh.json", scene_json(kWhite, shape));
    EXPECT_NE(err.find("nan.obj"), std::string::npos) << err;
}

TEST(JsonScene, DuplicateIdsAndUnknownShapeTypes) {
    EXPECT_NE(load_error("dup.json", scene_json(kWhite, kQuad + "," + kQuad)).find("duplicate shape id"),
              std::string::npos);
    std::string err =
        load_error("torus.json", scene_json(kWhite, R"({"id": "t", "type": "torus", "material": "white"})"));
    EXPECT_NE(err.find("shapes[0].type"), std::string::npos) << err;
    EXPECT_NE(err.find("torus"), std::string::npos) << err;
}

TEST(JsonScene, OverflowingNumberIsAnError) {
    // JSON has no NaN/Inf literal; 1e999 overflows, and the parser rejects it with a position.
    std::string shape =
        R"({"id": "l", "type": "rectangle", "material": "white", "emitter": {"type": "area", "radiance": [1e999, 1, 1]}})";
    std::string err = load_error("infrad.json", scene_json(kWhite, shape));
    EXPECT_NE(err.find("infrad.json"), std::string::npos) << err;
    EXPECT_NE(err.find("1e999"), std::string::npos) << err;
}

TEST(JsonScene, NonFinitePropIsAnError) {
    Props p;
    p.file = "x.json";
    p.where = "materials.m";
    p.values["reflectance"] = Eigen::Array3f(0.5f, std::nanf(""), 0.5f);
    try {
        p.get_rgb("reflectance");
        FAIL() << "expected SceneError";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("materials.m.reflectance"), std::string::npos) << e.what();
    }
}
