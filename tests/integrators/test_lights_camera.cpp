// Light sampling and camera geometry.
#include "core/camera.h"
#include "core/emitter.h"
#include "core/sampler.h"
#include "scene_fixtures.h"
#include <gtest/gtest.h>

using namespace lpt;

TEST(AreaLight, SamplePdfMatchesPdfAreaLight) {
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
    const Shape& light = scene.shapes[scene.find_shape("light")];
    Vec3f ref(0.1f, -0.2f, 0.f);
    for (uint32_t i = 0; i < 1000; ++i) {
        LightSample ls = sample_area_light(light, ref, Eigen::Vector3f(sample_1d(1, i, 0, 0), sample_1d(1, i, 0, 1), sample_1d(1, i, 0, 2)));
        ASSERT_TRUE(ls.valid());
        EXPECT_NEAR(ls.pdf, pdf_area_light(light, ref, ls.p, ls.n), 1e-4f * ls.pdf);
    }
}

TEST(AreaLight, InversePdfIntegratesSolidAngle) {
    // E[1/pdf] = solid angle subtended; for a centred rectangle at height h, the solid angle is
    // 4 atan(ab / (h sqrt(a^2 + b^2 + h^2))).
    const float a = 0.5f, b = 0.3f, h = 1.f;
    Scene scene = test::form_factor_scene(0.5f, 1.f, a, b, h);
    const Shape& light = scene.shapes[scene.find_shape("light")];
    double sum = 0, sum2 = 0;
    const int n = 200000;
    for (int i = 0; i < n; ++i) {
        LightSample ls = sample_area_light(light, Vec3f::Zero(), Eigen::Vector3f(sample_1d(2, i, 0, 0), sample_1d(2, i, 0, 1), sample_1d(2, i, 0, 2)));
        double v = ls.valid() ? 1.0 / ls.pdf : 0.0;
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
    double expected = 4 * std::atan(a * b / (h * std::sqrt(a * a + b * b + h * h)));
    EXPECT_NEAR(mean, expected, 4 * se + 1e-6);
}

TEST(AreaLight, BackSideEmitsNothing) {
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
    const Shape& light = scene.shapes[scene.find_shape("light")];
    LightSample ls = sample_area_light(light, Vec3f(0, 0, 2), Eigen::Vector3f(0.3f, 0.4f, 0.5f));
    EXPECT_FALSE(ls.valid());
}

TEST(LightSampler, PmfSumsToOneAndFollowsPower) {
    Scene scene = load_scene(test::cornell_box_path());
    double sum = 0;
    for (size_t i = 0; i < scene.emitters.size(); ++i) sum += scene.lights.pmf(int(i));
    EXPECT_NEAR(sum, 1.0, 1e-6);
}

TEST(Camera, CentreRayFollowsLookAtAndFovAxis) {
    Camera cam;
    cam.world_from_camera = Transform::look_at(Vec3f(0, 0, 0), Vec3f(0, 0, 5), Vec3f(0, 1, 0));
    cam.width = 200;
    cam.height = 100;
    cam.fov = 90.f;
    cam.fov_axis = FovAxis::X;
    Ray r = cam.generate_ray(Vec2f(100, 50));
    EXPECT_NEAR((r.d - Vec3f(0, 0, 1)).norm(), 0.f, 1e-6f);
    // Left edge of the image points to +x in camera space (Mitsuba): 45 degrees for fov 90 along x.
    Ray left = cam.generate_ray(Vec2f(0, 50));
    EXPECT_NEAR(left.d.x(), std::sqrt(0.5f), 1e-5f);
    EXPECT_NEAR(left.d.z(), std::sqrt(0.5f), 1e-5f);
    // Top edge: +y, with the vertical half-angle atan(tan(45)/aspect).
    Ray top = cam.generate_ray(Vec2f(100, 0));
    EXPECT_NEAR(std::atan2(top.d.y(), top.d.z()), std::atan(0.5f), 1e-5f);
    cam.fov_axis = FovAxis::Smaller;  // smaller = y here
    top = cam.generate_ray(Vec2f(100, 0));
    EXPECT_NEAR(std::atan2(top.d.y(), top.d.z()), kPi / 4, 1e-5f);
}

TEST(Camera, TentFilterSamplesTriangleDensity) {
    PixelFilter f{PixelFilter::Type::Tent, 1.f};
    // Mean |x| of a unit tent is 1/3; box of radius 0.5 gives 1/4.
    double s = 0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) s += std::abs(f.sample(Vec2f(sample_1d(5, i, 0, 0), 0.5f)).x());
    EXPECT_NEAR(s / n, 1.0 / 3.0, 0.005);
}
