// AOVs against geometry: a camera looking straight down at a plane sees its normal and the
// analytic distance h / cos(angle of the pixel's ray).
#include "integrators/aov.h"
#include "scene_fixtures.h"
#include <gtest/gtest.h>
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
/// straight down from height 1 at an 8 × 8 film; nothing else.
Scene emitter_edge_scene(float edge) {
    auto s = [](float v) { return std::to_string(v); };
    std::string json = R"({
      "camera": {"fov": )" +
                       s(kEdgeFov) +
                       R"(, "width": 8, "height": 8, "filter": {"type": "box"},
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
