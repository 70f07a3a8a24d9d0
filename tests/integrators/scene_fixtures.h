// Small analytic scenes for integrator tests, written as JSON so they also exercise the loader.
#pragma once
#include "core/scene_loader.h"
#include "test_util.h"
#include <string>

namespace lpt::test {

/// Closed sphere (radius 1) lined with a one-sided diffuse emitter of albedo `albedo` and
/// radiance `le`, normals flipped inward; camera at the centre. Exact radiance: le / (1 - albedo).
inline Scene furnace_scene(float albedo, float le, int max_depth = -1) {
    std::string a = std::to_string(albedo), l = std::to_string(le);
    std::string json = R"({
      "integrator": {"max_depth": )" +
                       std::to_string(max_depth) + R"(, "rr_depth": 3},
      "camera": {"fov": 60, "width": 8, "height": 8, "to_world": {"lookat": {"origin": [0,0,0], "target": [0,0,1], "up": [0,1,0]}}},
      "materials": {"wall": {"type": "diffuse", "reflectance": )" +
                       a + R"(}},
      "shapes": [{"id": "shell", "type": "sphere", "material": "wall", "flip_normals": true,
                  "emitter": {"type": "area", "radiance": )" +
                       l + R"(}}]
    })";
    return load_scene(write_temp_file("furnace.json", json));
}

/// Diffuse plane z=0 (albedo rho, facing +z) under a one-sided rectangle light of half sides
/// (a, b) at height h facing down, radiance le. The camera looks straight down at the origin with a
/// 0.5 degree field of view from height h/2, so every pixel sees the plane's centre.
inline Scene form_factor_scene(float rho, float le, float a, float b, float h) {
    auto s = [](float v) { return std::to_string(v); };
    std::string json = R"({
      "integrator": {"max_depth": 2, "rr_depth": 100},
      "camera": {"fov": 0.5, "width": 8, "height": 8, "filter": {"type": "box"}, "near_clip": 1e-4,
                 "to_world": {"lookat": {"origin": [0,0,)" +
                       s(h / 2) + R"(], "target": [0,0,0], "up": [0,1,0]}}},
      "materials": {"plane": {"type": "diffuse", "reflectance": )" +
                       s(rho) + R"(},
                    "black": {"type": "diffuse", "reflectance": 0}},
      "shapes": [
        {"id": "plane", "type": "rectangle", "material": "plane", "to_world": {"scale": [100, 100, 1]}},
        {"id": "light", "type": "rectangle", "material": "black",
         "to_world": [{"scale": [)" +
                       s(a) + "," + s(b) +
                       R"(, 1]}, {"rotate": {"axis": [1,0,0], "angle": 180}}, {"translate": [0,0,)" + s(h) + R"(]}],
         "emitter": {"type": "area", "radiance": )" +
                       s(le) + R"(}}]
    })";
    return load_scene(write_temp_file("form_factor.json", json));
}

/// Differential area to a parallel, centred rectangle of half sides (a, b) at height h:
/// four corner-rectangle form factors (Howell's catalogue, C-11).
inline double form_factor_centred_rectangle(double a, double b, double h) {
    double X = a / h, Y = b / h;
    double sx = std::sqrt(1 + X * X), sy = std::sqrt(1 + Y * Y);
    double corner = (X / sx * std::atan(Y / sx) + Y / sy * std::atan(X / sy)) / (2 * M_PI);
    return 4 * corner;
}

inline std::string cornell_box_path() { return std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json"; }

}  // namespace lpt::test
