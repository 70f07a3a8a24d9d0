// AOVs against geometry: a camera looking straight down at a plane sees its normal and the
// analytic distance h / cos(angle of the pixel's ray).
#include "integrators/aov.h"
#include "integrators/path.h"
#include "scene_fixtures.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>

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

namespace {

constexpr float kEdgeFov = 40.f;
/// World units a film pixel of emitter_edge_scene spans on its plane: the plane is perpendicular
/// to the view axis, so world x is linear in film x.
float edge_scene_pixel() { return 2.f * std::tan(0.5f * kEdgeFov * kPi / 180.f) / 8.f; }

/// An emissive rectangle covering world x >= edge (z = 0, facing up) under a camera looking
/// straight down from height 1 at an 8 × 8 film with `filter`; nothing else.
Scene emitter_edge_scene(float edge, const std::string& filter = "box") {
    auto s = [](float v) { return std::to_string(v); };
    std::string json = R"({
      "camera": {"fov": )" +
                       s(kEdgeFov) + R"(, "width": 8, "height": 8, "filter": {"type": ")" + filter + R"("},
                 "to_world": {"lookat": {"origin": [0,0,1], "target": [0,0,0], "up": [0,1,0]}}},
      "materials": {"black": {"type": "diffuse", "reflectance": 0}},
      "shapes": [{"id": "light", "type": "rectangle", "material": "black",
                  "to_world": [{"scale": [50, 100, 1]}, {"translate": [)" +
                       s(edge + 50.f) + R"(, 0, 0]}],
                  "emitter": {"type": "area", "radiance": 1}}]
    })";
    return load_scene(test::write_temp_file("emitter_edge.json", json));
}

}  // namespace

// The edge a quarter of a pixel from the film's centre line: every pixel on one side is covered,
// every pixel on the other is not, and the pixel the edge crosses is covered over three quarters
// of its width, its sub-cells on the dark neighbour's side empty (4 × 4 cells: one column empty,
// three full; 2 × 2: the column the edge halves at 0.5), the same in every row.
TEST(Aov, EmitterCellsPlaceTheEdgeInsideThePixel) {
    const Scene scene = emitter_edge_scene(0.25f * edge_scene_pixel());
    for (int cells : {4, 2}) {
        const std::vector<float> cov = render_emitter_cells(scene, 8, 8, cells);
        ASSERT_EQ(cov.size(), size_t(64 * cells * cells));
        auto at = [&](int x, int y, int cx, int cy) {
            return cov[size_t(y * 8 + x) * cells * cells + cy * cells + cx];
        };
        auto mean = [&](int x, int y) {
            float m = 0.f;
            for (int k = 0; k < cells * cells; ++k) m += cov[size_t(y * 8 + x) * cells * cells + k];
            return m / float(cells * cells);
        };
        // which side is lit depends on the film's orientation, not on what is tested here
        const bool lit_right = mean(7, 0) == 1.f;
        const int edge_px = lit_right ? 4 : 3, dark_cell = lit_right ? 0 : cells - 1;
        for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
                if (x == edge_px) {
                    EXPECT_FLOAT_EQ(mean(x, y), 0.75f) << "cells " << cells << " pixel " << x << "," << y;
                    for (int cy = 0; cy < cells; ++cy)
                        for (int cx = 0; cx < cells; ++cx)
                            EXPECT_FLOAT_EQ(at(x, y, cx, cy), cx != dark_cell ? 1.f
                                                              : cells == 4    ? 0.f
                                                                              : 0.5f)
                                << "cells " << cells << " pixel " << x << "," << y << " cell " << cx << "," << cy;
                } else {
                    EXPECT_EQ(mean(x, y), (x > edge_px) == lit_right ? 1.f : 0.f) << "pixel " << x << "," << y;
                }
            }
    }
}

// What the camera meets is what the film shows: an emitter a quarter of a pixel past the film's
// edge is not met, through a tent filter either, although the renderer's tent-filtered image
// (samples up to half a pixel past the edge) is lit there and its box-filtered one is black. The
// fit's target, from a picture at eight times the resolution, does not show it.
TEST(Aov, CameraSightsStopAtTheFilmsEdge) {
    const float past_the_edge = 4.25f * edge_scene_pixel();  // the film spans ±4 pixels
    for (const std::string filter : {"tent", "box"}) {
        const Scene scene = emitter_edge_scene(past_the_edge, filter);
        const CameraSights sights = camera_sights(scene, SceneSpectra<3>::from_description(scene), 8, 8);
        EXPECT_FALSE(sights.front_of.at(0)) << filter;
        EXPECT_TRUE(sights.nothing) << filter;
        EXPECT_EQ(sights.black_back_pixels, 0.f) << filter;
        RenderOptions opt = RenderOptions::from_scene(scene);
        opt.spp = 64;
        const std::vector<float> image = render_path<3>(scene, SceneSpectra<3>::from_description(scene), opt).develop();
        float brightest = 0.f;
        for (float v : image) brightest = std::max(brightest, v);
        EXPECT_EQ(brightest > 0.f, filter == "tent") << filter << ": the render's samples";
    }
    // and a quarter of a pixel inside the edge, it is met
    const Scene inside = emitter_edge_scene(3.75f * edge_scene_pixel(), "tent");
    EXPECT_TRUE(camera_sights(inside, SceneSpectra<3>::from_description(inside), 8, 8).front_of.at(0));
}

// The sides are the path tracer's: the same rectangle turned over shows the camera its black back.
TEST(Aov, CameraSightsTellAnEmittersBackFromItsFront) {
    Scene scene = emitter_edge_scene(-10.f);  // fills the film
    const CameraSights front = camera_sights(scene, SceneSpectra<3>::from_description(scene), 8, 8);
    EXPECT_TRUE(front.front_of.at(0));
    EXPECT_EQ(front.black_back_pixels, 0.f);
    EXPECT_FALSE(front.nothing);
    scene.camera.world_from_camera = Transform::look_at(Vec3f(0, 0, -1), Vec3f(0, 0, 0), Vec3f(0, 1, 0));  // from below
    scene.build();
    const CameraSights back = camera_sights(scene, SceneSpectra<3>::from_description(scene), 8, 8);
    EXPECT_FALSE(back.front_of.at(0));
    EXPECT_EQ(back.black_back_pixels, 64.f) << "the whole film, every ray";
    EXPECT_FALSE(back.nothing);
}

// A smooth-shaded sphere seen from outside shows no back worth a pixel, although along its
// silhouette the interpolated shading normal turns away from faces the camera sees (and a ray
// may slip between two triangles to the far side's inside); from inside, it shows its back.
TEST(Aov, CameraSightsSeeNoBackOnASpheresSilhouette) {
    const std::string json = R"({
      "camera": {"fov": 40, "width": 8, "height": 8, "filter": {"type": "box"},
                 "to_world": {"lookat": {"origin": [0,0,4], "target": [0,0,0], "up": [0,1,0]}}},
      "materials": {"m": {"type": "diffuse", "reflectance": 0.5}},
      "shapes": [{"id": "ball", "type": "sphere", "material": "m"}]
    })";
    Scene scene = load_scene(test::write_temp_file("sphere_sights.json", json));
    const CameraSights outside = camera_sights(scene, SceneSpectra<3>::from_description(scene), 8, 8, 32);
    EXPECT_TRUE(outside.front_of.at(0));
    EXPECT_TRUE(outside.nothing);
    EXPECT_GT(outside.black_back_pixels, 0.f) << "the silhouette's shading normals: else this tests nothing";
    EXPECT_LT(outside.black_back_pixels, 0.25f);
    scene.camera.world_from_camera = Transform::look_at(Vec3f(0, 0, 0.5f), Vec3f(0, 0, 0), Vec3f(0, 1, 0));
    const CameraSights inside = camera_sights(scene, SceneSpectra<3>::from_description(scene), 8, 8);
    EXPECT_FALSE(inside.front_of.at(0));
    EXPECT_NEAR(inside.black_back_pixels, 64.f, 0.5f);
}
