// AOVs against geometry: a camera looking straight down at a plane sees its normal and the
// analytic distance h / cos(angle of the pixel's ray).
#include "integrators/aov.h"
#include "scene_fixtures.h"
#include <gtest/gtest.h>

using namespace lpt;

TEST(Aov, PlaneNormalDistanceAlbedoAtAnyResolution) {
    const float h = 1.f;
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 2 * h);  // camera at height h
    scene.shapes.erase(scene.shapes.begin() + scene.find_shape("light"));
    scene.emitters.clear();
    scene.build();
    auto spectra = SceneSpectra<3>::from_description(scene);
    for (auto [w, hgt] : {std::pair{4, 4}, std::pair{7, 3}}) {
        AovImages aov = render_aovs(scene, spectra, w, hgt, 4, 0);
        ASSERT_EQ(aov.distance.size(), size_t(w * hgt));
        for (int i = 0; i < w * hgt; ++i) {
            EXPECT_NEAR(aov.normal[3 * i + 2], 1.f, 1e-5f);
            // fov 0.5 degrees: every ray is within 0.25 degrees of vertical.
            EXPECT_NEAR(aov.distance[i], h, h * (1.f / std::cos(0.25f * kPi / 180.f) - 1.f) + 1e-5f);
            EXPECT_NEAR(aov.albedo[3 * i], 0.5f, 1e-6f);
        }
    }
}

TEST(Aov, MissGivesZero) {
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 2.f);
    scene.camera.world_from_camera =
        Transform::look_at(Vec3f(0, 0, 1), Vec3f(0, 0, 5), Vec3f(0, 1, 0));  // looking up, past the light
    scene.shapes.erase(scene.shapes.begin() + scene.find_shape("light"));
    scene.emitters.clear();
    scene.build();
    auto spectra = SceneSpectra<3>::from_description(scene);
    AovImages aov = render_aovs(scene, spectra, 3, 3, 2, 0);
    for (float d : aov.distance) EXPECT_EQ(d, 0.f);
    for (float n : aov.normal) EXPECT_EQ(n, 0.f);
}
