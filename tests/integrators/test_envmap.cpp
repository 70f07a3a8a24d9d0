// Environment map emitter against mathematics: the sampling density is a normalised pdf that
// matches what sample() draws (per-texel histogram), a constant map renders exactly like the
// constant emitter (convex diffuse sphere: L_o = albedo · L), and a single bright texel lights
// a plane like a directional light of the texel's irradiance (analytic, by quadrature over the
// texel), for NEE, BSDF sampling and MIS. The classroom's missing map is a clear error.
#include "core/envmap.h"
#include "core/image_io.h"
#include "core/sampler.h"
#include "core/warp.h"
#include "integrators/path.h"
#include "scene_fixtures.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace lpt;
using namespace lpt::test;

namespace {

std::shared_ptr<BitmapData> make_map(int w, int h, const std::function<Eigen::Array3f(int, int)>& f) {
    auto b = std::make_shared<BitmapData>();
    b->width = w;
    b->height = h;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            Eigen::Array3f c = f(i, j);
            b->rgb.insert(b->rgb.end(), {c[0], c[1], c[2]});
        }
    return b;
}

std::string write_map(const std::string& name, int w, int h, const std::function<Eigen::Array3f(int, int)>& f) {
    auto b = make_map(w, h, f);
    const std::string path = write_temp_file(name, "");
    write_exr(path, Image{w, h, 3, b->rgb, {"R", "G", "B"}});
    return path;
}

double mean_channel(const std::vector<float>& img, int c) {
    double s = 0;
    for (size_t i = c; i < img.size(); i += 3) s += img[i];
    return s / double(img.size() / 3);
}

std::vector<float> render(const Scene& scene, int spp, LightStrategy strat) {
    auto spectra = SceneSpectra<3>::from_description(scene);
    RenderOptions opt = RenderOptions::from_scene(scene);
    opt.spp = spp;
    opt.seed = 11;
    opt.strategy = strat;
    return render_path<3>(scene, spectra, opt).develop();
}

}  // namespace

TEST(EnvMap, PdfIsNormalisedAndMatchesSampling) {
    // A map with structure in both axes, rotated, with black texels (pdf 0 there).
    auto img = make_map(16, 8, [](int i, int j) {
        const float v = (i == 3 && j == 2) ? 40.f : (j == 6 ? 0.f : 0.2f + 0.1f * float((i * 7 + j * 3) % 5));
        return Eigen::Array3f(v, 0.5f * v, 2.f * v);
    });
    img->path = "generated";
    EnvMap env(img, Transform::rotate(Vec3f(0.3f, 1.f, 0.2f).normalized(), 35.f), 2.f);
    // ∫ pdf dω = 1 by uniform-sphere Monte Carlo; sample().pdf = pdf(sample().wi).
    double integral = 0;
    const int n = 400000;
    for (int k = 0; k < n; ++k) {
        const Vec3f w = sample_uniform_sphere(Vec2f(sample_1d(1, k, 0, 0), sample_1d(1, k, 0, 1)));
        integral += env.pdf(w) / pdf_uniform_sphere(w);
    }
    EXPECT_NEAR(integral / n, 1.0, 0.02);
    std::vector<double> hist(16 * 8, 0.0);
    for (int k = 0; k < n; ++k) {
        LightSample ls = env.sample(Vec2f(sample_1d(2, k, 0, 0), sample_1d(2, k, 0, 1)));
        ASSERT_TRUE(ls.valid());
        EXPECT_NEAR(ls.pdf, env.pdf(ls.wi), 2e-3f * ls.pdf);
        EXPECT_GT(luminance(env.eval(ls.wi)), 0.f);  // never a black texel
    }
    // The same ∫ in another form: E_sample[L / pdf] = ∫ L dω = 4π · mean radiance.
    double est = 0;
    for (int k = 0; k < n; ++k) {
        LightSample ls = env.sample(Vec2f(sample_1d(3, k, 0, 0), sample_1d(3, k, 0, 1)));
        est += luminance(env.eval(ls.wi)) / ls.pdf;
    }
    EXPECT_NEAR(est / n / (4 * kPi), luminance(env.mean_radiance()), 2e-3 * luminance(env.mean_radiance()));
}

TEST(EnvMap, ConstantMapEqualsConstantEmitter) {
    // Convex diffuse sphere (albedo 0.5) in a uniform sky of radiance 0.8: every sphere pixel is
    // 0.4, every sky pixel 0.8, whatever the emitter; the map is rotated to make sure that does
    // not matter.
    const std::string map = write_map("const_sky.exr", 8, 4, [](int, int) { return Eigen::Array3f::Constant(0.8f); });
    auto scene_with = [&](const std::string& emitter) {
        return load_scene(write_temp_file("env_sphere.json", R"({
          "integrator": {"max_depth": -1, "rr_depth": 100},
          "camera": {"fov": 40, "width": 16, "height": 16, "to_world": {"lookat": {"origin": [0,0,4], "target": [0,0,0], "up": [0,1,0]}}},
          "materials": {"m": {"type": "diffuse", "reflectance": 0.5}},
          "shapes": [{"id": "ball", "type": "sphere", "material": "m"}],
          "emitters": [)" + emitter + R"(]
        })"));
    };
    Scene constant = scene_with(R"({"type": "constant", "radiance": 0.8})");
    Scene envmap = scene_with(R"({"type": "envmap", "filename": ")" + map +
                              R"(", "to_world": {"rotate": {"axis": [1,1,0], "angle": 70}}})");
    for (LightStrategy s : {LightStrategy::Mis, LightStrategy::Nee, LightStrategy::Bsdf}) {
        const std::vector<float> a = render(constant, 64, s), b = render(envmap, 64, s);
        // The tessellated sphere's silhouette pixels mix sky and ball identically in both.
        EXPECT_NEAR(mean_channel(b, 1), mean_channel(a, 1), 0.01 * mean_channel(a, 1)) << int(s);
        for (size_t i = 0; i < a.size(); i += 3) {
            // Sky: every sample escaped, so the constant emitter's pixel is 0.8 to float round-off; a
            // silhouette pixel whose noisy ball samples happen to average near 0.8 is not.
            const bool sky = std::abs(a[i] - 0.8f) < 1e-6f;
            if (sky) {
                EXPECT_NEAR(b[i], 0.8f, 1e-5f);  // escaped camera rays see the map exactly
            }
        }
    }
}

TEST(EnvMap, SingleTexelIsADirectionalLight) {
    // 32 x 16 map, black but texel (5, 4) of radiance 500. A diffuse plane (albedo 0.6, normal
    // +y) seen from above: L_o = (albedo / π) · E, E = 500 ∫_texel max(0, n·ω) dω.
    const int W = 32, H = 16, ti = 5, tj = 4;
    const float Lt = 500.f, albedo = 0.6f;
    const std::string map = write_map(
        "texel_sky.exr", W, H, [&](int i, int j) { return Eigen::Array3f::Constant(i == ti && j == tj ? Lt : 0.f); });
    // Quadrature over the texel in (u, v): dω = 2π² sin θ du dv; ω_y = cos θ (identity to_world).
    double E = 0;
    const int q = 400;
    for (int a = 0; a < q; ++a)
        for (int b = 0; b < q; ++b) {
            const double v = (tj + (b + 0.5) / q) / H, theta = v * kPi;
            const double du = 1.0 / (W * q), dv = 1.0 / (H * q);
            E += Lt * std::max(0.0, std::cos(theta)) * 2 * kPi * kPi * std::sin(theta) * du * dv;
        }
    const double expected = albedo / kPi * E;
    Scene scene = load_scene(write_temp_file("env_plane.json", R"({
      "integrator": {"max_depth": 2, "rr_depth": 100},
      "camera": {"fov": 1, "width": 8, "height": 8, "filter": {"type": "box"},
                 "to_world": {"lookat": {"origin": [0,1,0], "target": [0,0,0], "up": [0,0,1]}}},
      "materials": {"m": {"type": "diffuse", "reflectance": 0.6}},
      "shapes": [{"id": "plane", "type": "rectangle", "material": "m",
                  "to_world": [{"scale": 100}, {"rotate": {"axis": [1,0,0], "angle": -90}}]}],
      "emitters": [{"type": "envmap", "filename": ")" + map + R"("}]
    })"));
    for (LightStrategy s : {LightStrategy::Nee, LightStrategy::Mis, LightStrategy::Bsdf}) {
        // BSDF sampling finds a 1/512-of-the-sphere texel rarely: give it more samples.
        const std::vector<float> img = render(scene, s == LightStrategy::Bsdf ? 16384 : 256, s);
        EXPECT_NEAR(mean_channel(img, 0), expected, (s == LightStrategy::Bsdf ? 0.03 : 0.002) * expected) << int(s);
    }
}

TEST(EnvMap, MissingMapNamesTheFile) {
    const std::string json =
        R"({"camera": {"fov": 40}, "shapes": [], "emitters": [{"type": "envmap", "filename": "no_such_sky.exr"}]})";
    try {
        load_scene(write_temp_file("env_missing.json", json));
        FAIL() << "accepted a missing map";
    } catch (const std::exception& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("no_such_sky.exr"), std::string::npos) << msg;
        EXPECT_NE(msg.find("emitters[0].filename"), std::string::npos) << msg;
    }
    const std::string shared = shared_dir();
    if (shared.empty()) return;
    // The classroom's scene.xml names an envmap that is not distributed (classroom/SOURCE.txt).
    try {
        load_scene(shared + "/scenes/classroom/scene.xml");
        FAIL() << "classroom/scene.xml loaded without its envmap";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("spaichingen_hill_2k.exr"), std::string::npos) << e.what();
    }
}
