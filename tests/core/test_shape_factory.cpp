// make_shape / make_*_emitter: the factories both scene loaders call.
#include "core/emitter.h"
#include "core/shape_factory.h"
#include <gtest/gtest.h>

using namespace lpt;

namespace {

Props props(const std::string& type) {
    Props p;
    p.type = type;
    p.file = "scene.test";
    p.where = "shapes[0]";
    return p;
}

}  // namespace

TEST(ShapeFactory, SphereIsToWorldAfterCentreAndRadius) {
    Props p = props("sphere");
    p.values["radius"] = 2.f;
    p.values["center"] = Eigen::Array3f(1, 0, 0);
    p.values["to_world"] = Transform::scale(Vec3f::Constant(3.f));  // Mitsuba: to_world · T(c) · S(r)
    const Shape s = make_shape(p, kMitsubaShapeDefaults);
    for (const Vec3f& v : s.mesh.positions) EXPECT_NEAR((v - Vec3f(3, 0, 0)).norm(), 6.f, 1e-4f);
}

TEST(ShapeFactory, FlipNormalsTurnsTheSurfaceInsideOut) {
    Props p = props("rectangle");
    Shape up = make_shape(p, kJsonShapeDefaults);
    p.values["flip_normals"] = true;
    Shape down = make_shape(p, kJsonShapeDefaults);
    up.prepare();
    down.prepare();
    for (uint32_t t = 0; t < 2; ++t) {
        EXPECT_NEAR(up.face_normal(t).z(), 1.f, 1e-6f);
        EXPECT_NEAR(down.face_normal(t).z(), -1.f, 1e-6f);  // winding reversed
    }
    for (const Vec3f& n : down.mesh.normals) EXPECT_NEAR(n.z(), -1.f, 1e-6f);
}

TEST(ShapeFactory, ErrorsNameTheFileAndField) {
    Props p = props("sphere");
    p.values["radius"] = -1.f;
    try {
        make_shape(p, kJsonShapeDefaults);
        FAIL() << "a negative radius must be refused";
    } catch (const SceneError& e) {
        EXPECT_EQ(e.field(), "shapes[0].radius");
        EXPECT_EQ(e.file(), "scene.test");
    }
    Props missing = props("obj");
    missing.values["filename"] = std::string("/nonexistent/mesh.obj");
    try {
        make_shape(missing, kJsonShapeDefaults);
        FAIL() << "a missing mesh file must be refused";
    } catch (const SceneError& e) {
        EXPECT_EQ(e.field(), "shapes[0].filename");
        EXPECT_NE(std::string(e.what()).find("mesh.obj"), std::string::npos) << e.what();
    }
}

TEST(EmitterFactory, AreaAndConstantTakeTheirRadiance) {
    Props a = props("area");
    a.values["radiance"] = Eigen::Array3f(1, 2, 3);
    const Emitter area = make_area_emitter(a, 4);
    EXPECT_EQ(area.kind, EmitterKind::Area);
    EXPECT_EQ(area.shape, 4);
    EXPECT_FLOAT_EQ(area.radiance_rgb[2], 3.f);
    Props c = props("constant");
    c.values["radiance"] = 0.5f;
    const Emitter sky = make_environment_emitter(c);
    EXPECT_EQ(sky.kind, EmitterKind::Constant);
    EXPECT_FLOAT_EQ(sky.radiance_rgb[0], 0.5f);
    EXPECT_THROW(make_area_emitter(c, 0), SceneError);
}
