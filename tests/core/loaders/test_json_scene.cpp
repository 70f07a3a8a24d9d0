// JSON scene loader: valid scenes load; every kind of bad input is a SceneError that names the
// file and the field.
#include "core/error.h"
#include "core/props.h"
#include <cmath>
#include "core/scene_loader.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <regex>

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
    // Array elements by index: a shape's material, one component of a colour.
    const std::string two = test::write_temp_file(
        "defines2.json",
        scene_json(kWhite + R"(, "grey": {"type": "diffuse", "reflectance": [0.2, 0.2, 0.2]})",
                   kQuad + ", " + std::regex_replace(kQuad, std::regex(R"("id": "q")"), R"("id": "q2")")));
    s = load_scene(two, {{"shapes.1.material", "grey"}, {"materials.white.reflectance.1", "0.25"}});
    EXPECT_EQ(s.materials[s.shapes[0].material].get_rgb("reflectance").y(), 0.25f);
    EXPECT_NE(s.shapes[0].material, s.shapes[1].material);
    EXPECT_EQ(s.materials[s.shapes[1].material].get_rgb("reflectance").y(), 0.2f);
    for (const char* bad : {"shapes.2.material", "shapes.x.material", "shapes.-1.material", "camera.fov.x"}) try {
            load_scene(two, {{bad, "grey"}});
            ADD_FAILURE() << bad << " loaded";
        } catch (const SceneError& e) {
            EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << bad << ": " << e.what();
        }
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

TEST(JsonScene, UnknownKeysNameTheirPath) {
    // A misspelt key left its default in place without a word; now each is an error naming it.
    const std::pair<std::string, std::string> cases[] = {
        {scene_json(kWhite, kQuad, R"(, "emiters": [])"), "emiters"},
        {scene_json(kWhite, kQuad, R"(, "integrator": {"max_dept": 3})"), "integrator.max_dept"},
        {scene_json(kWhite, R"({"id": "s", "type": "sphere", "material": "white", "radus": 2})"), "shapes[0].radus"},
        {scene_json(kWhite, R"({"id": "s", "type": "rectangle", "material": "white", "filename": "a.obj"})"),
         "shapes[0].filename"},
        {scene_json(kWhite, R"({"id": "s", "type": "cube", "material": "white",
                               "to_world": {"rotate": {"axis": [0,1,0], "angle": 30, "angel": 3}}})"),
         "shapes[0].to_world.rotate.angel"},
        {scene_json(kWhite, kQuad, R"(, "emitters": [{"type": "envmap", "filenme": "sky.exr"}])"),
         "emitters[0].filenme"},
    };
    for (const auto& [json, field] : cases) {
        const std::string err = load_error("unknown_key.json", json);
        EXPECT_NE(err.find("unknown_key.json"), std::string::npos) << err;
        EXPECT_NE(err.find(field), std::string::npos) << field << ": " << err;
        EXPECT_NE(err.find("unknown key"), std::string::npos) << err;
    }
    std::string camera = kCamera;
    camera.replace(camera.find("\"fov\""), 5, "\"fvo\"");
    const std::string err = load_error(
        "camera_key.json", "{" + camera + R"(, "materials": {)" + kWhite + R"(}, "shapes": [)" + kQuad + "]}");
    EXPECT_NE(err.find("camera.fvo"), std::string::npos) << err;
    // An edits file given as a scene says what it is.
    const std::string edits =
        load_error("edits.json", R"({"frames": 4, "camera": {"orbit": {"azimuth": [0, 30]}}, "shapes": []})");
    EXPECT_NE(edits.find("edits.json: field 'frames': this is an edits file"), std::string::npos) << edits;
    // Keys starting with '_' are comments, as the bundled scenes' "_comment".
    EXPECT_EQ(load_error("comment.json", scene_json(kWhite, kQuad, R"(, "_comment": "a note")")), "");
}

TEST(JsonScene, MisspeltDefineIsAnError) {
    const std::string path = test::write_temp_file("define_typo.json", scene_json(kWhite, kQuad));
    try {
        load_scene(path, {{"integrator.max_dept", "3"}});
        FAIL() << "a -D path the scene has no key for loaded";
    } catch (const SceneError& e) {
        EXPECT_NE(std::string(e.what()).find("integrator.max_dept"), std::string::npos) << e.what();
    }
}

TEST(JsonScene, PropertiesNoReaderAsksForAreErrors) {
    // Materials: the BSDF's readers decide what it takes.
    std::string err = load_error("mat_typo.json",
                                 scene_json(R"("white": {"type": "diffuse", "reflectanse": [0.5, 0.5, 0.5]})", kQuad));
    EXPECT_NE(err.find("materials.white.reflectanse"), std::string::npos) << err;
    EXPECT_NE(err.find("it reads reflectance"), std::string::npos) << err;
    err = load_error("nested_typo.json",
                     scene_json(R"("white": {"type": "twosided", "bsdf": {"type": "diffuse", "colour": 0.5}})", kQuad));
    EXPECT_NE(err.find("colour"), std::string::npos) << err;
    // Emitters likewise.
    const std::string light =
        R"({"id": "l", "type": "rectangle", "material": "white", "emitter": {"type": "area", "radiance": 1, "scale": 2}})";
    err = load_error("emit_typo.json", scene_json(kWhite, light));
    EXPECT_NE(err.find("shapes[0].emitter.scale"), std::string::npos) << err;
    // What the readers do ask for still loads, defaults included.
    EXPECT_EQ(
        load_error("known.json", scene_json(R"("p": {"type": "plastic", "diffuse_reflectance": 0.3, "int_ior": 1.5})",
                                            R"({"id": "q", "type": "rectangle", "material": "p"})")),
        "");
}

TEST(JsonScene, NegativeColoursAreErrors) {
    std::string err = load_error("neg_refl.json",
                                 scene_json(R"("white": {"type": "diffuse", "reflectance": [0.5, -0.1, 0.5]})", kQuad));
    EXPECT_NE(err.find("materials.white.reflectance"), std::string::npos) << err;
    EXPECT_NE(err.find(">= 0"), std::string::npos) << err;
    err = load_error("neg_spec.json", scene_json(R"("glass": {"type": "dielectric", "specular_transmittance": -1})",
                                                 R"({"id": "q", "type": "rectangle", "material": "glass"})"));
    EXPECT_NE(err.find("materials.glass.specular_transmittance"), std::string::npos) << err;
    const std::string light =
        R"({"id": "l", "type": "rectangle", "material": "white", "emitter": {"type": "area", "radiance": [1, -2, 1]}})";
    err = load_error("neg_rad.json", scene_json(kWhite, light));
    EXPECT_NE(err.find("shapes[0].emitter.radiance"), std::string::npos) << err;
    err = load_error("neg_env.json",
                     scene_json(kWhite, kQuad, R"(, "emitters": [{"type": "constant", "radiance": -1}])"));
    EXPECT_NE(err.find("radiance"), std::string::npos) << err;
    EXPECT_NE(err.find(">= 0"), std::string::npos) << err;
}

TEST(JsonScene, DegenerateLookatSaysWhy) {
    const std::pair<std::string, std::string> cases[] = {
        {R"({"origin": [0,0,1], "target": [0,0,1], "up": [0,1,0]})", "coincide"},
        {R"({"origin": [0,0,1], "target": [0,0,0], "up": [0,0,0]})", "zero length"},
        {R"({"origin": [0,0,1], "target": [0,0,0], "up": [0,0,2]})", "parallel"},
    };
    for (const auto& [lookat, why] : cases) {
        const std::string json = R"({"camera": {"to_world": {"lookat": )" + lookat + R"(}}, "materials": {)" + kWhite +
                                 R"(}, "shapes": [)" + kQuad + "]}";
        const std::string err = load_error("lookat.json", json);
        EXPECT_NE(err.find("camera.to_world"), std::string::npos) << err;
        EXPECT_NE(err.find(why), std::string::npos) << why << ": " << err;
    }
}
