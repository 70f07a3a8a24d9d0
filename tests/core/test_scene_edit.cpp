// Edit sequences: keyframe interpolation, transforms about the pivot, camera orbit geometry,
// frames that do not accumulate, and errors naming the edits file and field.
#include "core/error.h"
#include "core/image_io.h"
#include "core/scene_edit.h"
#include "core/scene_loader.h"
#include "test_util.h"
#include <gtest/gtest.h>

using namespace lpt;

namespace {
Scene cornell() { return load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json"); }
Vec3f centroid(const TriangleMesh& m) {
    Vec3f c = Vec3f::Zero();
    for (const Vec3f& p : m.positions) c += p;
    return c / float(m.positions.size());
}
std::string edit_error(const Scene& s, const std::string& json) {
    try {
        load_edits(test::write_temp_file("edits.json", json), s);
    } catch (const SceneError& e) {
        return e.what();
    }
    return "";
}
}  // namespace

TEST(SceneEdit, KeyframesInterpolateLinearly) {
    Track t{{Vec3f(0, 0, 0), Vec3f(2, 0, 0), Vec3f(2, 4, 0)}};
    EXPECT_TRUE(t.at(0.f).isApprox(Vec3f(0, 0, 0)));
    EXPECT_TRUE(t.at(0.25f).isApprox(Vec3f(1, 0, 0)));
    EXPECT_TRUE(t.at(0.75f).isApprox(Vec3f(2, 2, 0)));
    EXPECT_TRUE(t.at(1.f).isApprox(Vec3f(2, 4, 0)));
    EXPECT_TRUE(Track{{Vec3f(3, 3, 3)}}.at(0.6f).isApprox(Vec3f(3, 3, 3)));
}

TEST(SceneEdit, ShapesMoveAboutTheirCentreAndFramesDoNotAccumulate) {
    Scene s = cornell();
    std::vector<TriangleMesh> original;
    for (const Shape& sh : s.shapes) original.push_back(sh.mesh);
    const Camera cam = s.camera;
    EditSequence e = load_edits(test::write_temp_file("e1.json", R"({"frames": 2, "shapes": [
        {"id": "light", "translate": [[0, 0, 0], [1, 0, 0]]},
        {"id": "tall_block", "rotate": {"axis": [0, 1, 0], "angle": [0, 90]}, "scale": 2}]})"),
                                s);
    const int light = s.find_shape("light"), tall = s.find_shape("tall_block");
    const Vec3f c_light = centroid(original[light]);
    const float area_tall = s.shapes[tall].area();
    for (int rep = 0; rep < 2; ++rep) {  // the same t twice: no accumulation
        apply_edits(e, 0.5f, original, cam, s);
        EXPECT_TRUE(centroid(s.shapes[light].mesh).isApprox(c_light + Vec3f(0.5f, 0, 0), 1e-5f));
        EXPECT_NEAR(s.shapes[tall].area(), 4.f * area_tall, 1e-3f * area_tall);  // scale 2: area x 4
    }
    // About the pivot (the original bounding-box centre): p -> c + R(45 deg) * 2 * (p - c).
    Eigen::AlignedBox3f box;
    for (const Vec3f& p : original[tall].positions) box.extend(p);
    const Vec3f c = box.center();
    const Eigen::Matrix3f r = Eigen::AngleAxisf(kPi / 4, Vec3f::UnitY()).toRotationMatrix();
    for (size_t k = 0; k < original[tall].positions.size(); ++k)
        EXPECT_LT((s.shapes[tall].mesh.positions[k] - (c + r * (2.f * (original[tall].positions[k] - c)))).norm(),
                  1e-4f)
            << k;
    apply_edits(e, 0.f, original, cam, s);
    EXPECT_EQ(s.shapes[light].mesh.positions, original[light].positions);
}

TEST(SceneEdit, OrbitKeepsDistanceToPivotAndTurnsByTheAngle) {
    Scene s = cornell();
    std::vector<TriangleMesh> original;
    for (const Shape& sh : s.shapes) original.push_back(sh.mesh);
    const Camera cam = s.camera;
    EditSequence e = load_edits(
        test::write_temp_file("e2.json", R"({"camera": {"orbit": {"azimuth": 90, "pivot": [2.78, 2.73, 2.8]}}})"), s);
    apply_edits(e, 0.f, original, cam, s);
    const Vec3f pivot(2.78f, 2.73f, 2.8f);
    const Vec3f o0 = cam.world_from_camera.point(Vec3f::Zero()), o1 = s.camera.world_from_camera.point(Vec3f::Zero());
    EXPECT_NEAR((o0 - pivot).norm(), (o1 - pivot).norm(), 1e-4f);
    EXPECT_NEAR((o0 - pivot).normalized().dot((o1 - pivot).normalized()), 0.f, 1e-5f);  // 90 degrees
}

TEST(SceneEdit, ErrorsNameFileAndField) {
    Scene s = cornell();
    std::string err = edit_error(s, R"({"shapes": [{"id": "teapot", "translate": [1, 0, 0]}]})");
    EXPECT_NE(err.find("edits.json"), std::string::npos) << err;
    EXPECT_NE(err.find("shapes[0].id"), std::string::npos) << err;
    EXPECT_NE(err.find("teapot"), std::string::npos) << err;
    EXPECT_NE(edit_error(s, R"({"shapes": [{"id": "light", "translate": [1, 0]}]})").find("shapes[0].translate"),
              std::string::npos);
    EXPECT_NE(edit_error(s, R"({"shapes": [{"id": "light", "spin": 3}]})").find("shapes[0].spin"), std::string::npos);
    EXPECT_NE(edit_error(s, R"({"frames": 0})").find("frames"), std::string::npos);
    EXPECT_NE(edit_error(s, R"({"frames": 4294967297})").find("frames"), std::string::npos);  // wrapped to 1
    EXPECT_NE(edit_error(s, R"({"camera": {"zoom": 2}})").find("camera"), std::string::npos);
    EXPECT_NE(edit_error(s, R"({"frames": )").find("malformed"), std::string::npos);
}

// A misspelt key used to leave its default in place: "azimut" rendered 60 frames of an unmoved
// camera. Every object of the format now names its unknown key; '_' keys stay comments.
TEST(SceneEdit, MisspeltKeysAreErrorsEverywhere) {
    Scene s = cornell();
    const auto fails_at = [&](const std::string& json, const std::string& field) {
        const std::string err = edit_error(s, json);
        EXPECT_NE(err.find("field '" + field + "'"), std::string::npos) << json << " -> " << err;
        return err;
    };
    EXPECT_NE(fails_at(R"({"camera": {"orbit": {"azimut": [0, 30]}}})", "camera.orbit.azimut").find("azimuth"),
              std::string::npos);
    fails_at(R"({"camera": {"lookat": {"origin": [0, 0, 5], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 40}}})",
             "camera.lookat.fov");
    fails_at(R"({"camera": {"orbit": {"azimuth": 10}, "zoom": 2}})", "camera.zoom");
    fails_at(R"({"camera": {"orbit": {"azimuth": 10}, "lookat": {}}})", "camera");
    fails_at(R"({"camera": {"orbit": 30}})", "camera.orbit");
    fails_at(R"({"camera": {"orbit": {"up": [0, 0, 0]}}})", "camera.orbit.up");
    fails_at(R"({"shapes": [{"id": "light", "rotate": {"axis": [0, 1, 0], "angle": 10, "degrees": 1}}]})",
             "shapes[0].rotate.degrees");
    fails_at(R"({"shapes": [{"id": "light", "translate": [1, 0, 0], "scael": 2}]})", "shapes[0].scael");
    fails_at(R"({"frames": 2, "frame": 3})", "frame");
    fails_at(R"({"shapes": [{"id": "light", "translate": [1e39, 0, 0]}]})", "shapes[0].translate");
    fails_at(R"({"camera": {"orbit": {"azimuth": [0, 1e39]}}})", "camera.orbit.azimuth[1]");
    fails_at(R"({"shapes": [{"id": "light", "scale": 1e39}]})", "shapes[0].scale");
    // The scene reader's words for a wrong type (one number check serves both formats).
    EXPECT_NE(fails_at(R"({"shapes": [{"id": "light", "translate": [1, "0", 0]}]})", "shapes[0].translate")
                  .find("expected a number, got string"),
              std::string::npos);
    EXPECT_EQ(edit_error(s, R"({"_comment": "x", "camera": {"orbit": {"_why": "y", "azimuth": 10}}})"), "");
}

TEST(SceneEdit, UneditedOnlyWhereEveryTrackIsItsIdentity) {
    Scene s = cornell();
    EditSequence e = load_edits(test::write_temp_file("e3.json", R"({"frames": 4, "shapes": [
        {"id": "light", "translate": [[0, 0, 0], [1, 0, 0], [0, 0, 0]]},
        {"id": "tall_block", "scale": [[1, 1, 1], [2, 2, 2], [1, 1, 1]]}],
        "camera": {"orbit": {"azimuth": [0, 30, 0], "pivot": [2.78, 2.73, 2.8]}}})"),
                                s);
    EXPECT_TRUE(is_unedited(e, 0.f));
    EXPECT_FALSE(is_unedited(e, 0.25f));
    EXPECT_TRUE(is_unedited(e, 1.f));
    e.shapes[1].scale = Track{{Vec3f(1, 1, 1.5f)}};
    EXPECT_FALSE(is_unedited(e, 0.f));  // a constant scale edits every frame
    e.shapes.clear();
    e.camera.elevation = Track{{Vec3f(5, 0, 0)}};
    EXPECT_FALSE(is_unedited(e, 0.f));
    e.camera.kind = CameraEdit::Kind::LookAt;  // a look-at camera is never the loaded one
    e.camera.elevation = Track{{Vec3f::Zero()}};
    EXPECT_FALSE(is_unedited(e, 0.f));
    EXPECT_TRUE(is_unedited(EditSequence{}, 0.5f));
}

// A frame whose tracks are all at rest is the loaded scene bit for bit (render --edit scores it
// against the training view's reference, and the frame cache shares it between sequences):
// moving a mesh by the identity renormalises its shading normals, which rounds some of them.
TEST(SceneEdit, AnUneditedFrameIsTheLoadedSceneBitForBit) {
    std::string box = read_file(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json");
    box.insert(box.rfind(']'), R"(, { "id": "ball", "type": "sphere", "center": [1.3, 0.7, 1.9], "radius": 0.7,
        "material": "white" })");
    Scene s = load_scene(test::write_temp_file("ball.json", box));
    std::vector<TriangleMesh> original;
    for (const Shape& sh : s.shapes) original.push_back(sh.mesh);
    const Camera cam = s.camera;
    EditSequence e = load_edits(test::write_temp_file("e4.json", R"({"frames": 2, "shapes": [
        {"id": "tall_block", "rotate": {"axis": [0, 1, 0], "angle": [0, 40]}},
        {"id": "short_block", "translate": [[0, 0, 0], [0.3, 0, 0]], "pivot": [1.1, 0.2, 0.7]},
        {"id": "ball", "translate": [[0, 0, 0], [0.45, 0, 0.4]]}],
        "camera": {"orbit": {"azimuth": [0, 24], "elevation": [0, 6], "pivot": [2.78, 2.73, 2.8]}}})"),
                                s);
    apply_edits(e, 0.5f, original, cam, s);  // edited, then back at rest
    apply_edits(e, 0.f, original, cam, s);
    ASSERT_TRUE(is_unedited(e, 0.f));
    ASSERT_FALSE(original[s.find_shape("ball")].normals.empty());
    for (size_t i = 0; i < s.shapes.size(); ++i) {
        EXPECT_EQ(s.shapes[i].mesh.positions, original[i].positions) << i;
        EXPECT_EQ(s.shapes[i].mesh.normals, original[i].normals) << i;
    }
    EXPECT_EQ(s.camera.world_from_camera.m, cam.world_from_camera.m);
}
