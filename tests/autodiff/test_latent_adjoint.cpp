// Path replay gradients against central finite differences of the primal renderer, for every
// parameter kind, with common random numbers. Loss = Σ W · Ĩ with fixed random weights W, so
// d_image = W. Russian roulette is off: its survival probability depends on |β| and would make
// the primal discontinuous in the reflectances.
#include "autodiff/latent_path_adjoint.h"
#include "core/sampler.h"
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <algorithm>
#include <set>
#include <cmath>
#include <iostream>

using namespace lpt;

namespace {

Scene small_cornell(int max_depth = 4) {
    return load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json",
                      {{"camera.width", "8"},
                       {"camera.height", "8"},
                       {"integrator.max_depth", std::to_string(max_depth)},
                       {"integrator.rr_depth", "100"}});
}

RenderOptions opts(const Scene& s) {
    RenderOptions o = RenderOptions::from_scene(s);
    o.spp = 4;
    o.seed = 3;
    return o;
}

std::vector<float> weights(size_t n) { return test::random_weights(n, 77); }

double loss(LatentModel& m, const RenderOptions& o, const std::vector<float>& w) {
    m.sync();
    auto img = render_latent_terms<kLatentChannels>(m.scene(), m.spectra(), m.terms(), o).sum();
    double l = 0;
    for (size_t i = 0; i < img.size(); ++i) l += double(w[i]) * img[i];
    return l;
}

/// Checks grad_values of every slice (channels 0, 7, 15) against central differences of the
/// values: step 0.1 for the vectors Ĩ is linear in (exact up to rounding), 1e-2 for BSDF
/// coefficients (Ĩ is a polynomial in them; truncation ~h^2). Tolerance: relative `tol`, with a
/// floor of 1e-2 of the largest derivative so that rounding in near-zero ones does not count.
/// `nonzero_fraction`: share of checks whose derivative must be non-negligible (a scene that
/// does not exercise its parameters proves nothing). Returns the slices with one, by name.
std::set<std::string> check_all_slices(LatentModel& m, const RenderOptions& o, double tol,
                                       double nonzero_fraction = 0.5) {
    const std::vector<float> w = weights(size_t(m.scene().camera.width) * m.scene().camera.height * kLatentChannels);
    m.params().zero_grad();
    backward_latent(m, o, w);
    const std::vector<float> grad = m.params().grad_values();
    struct Check {
        std::string what;
        double g, fd;
    };
    std::vector<Check> checks;
    for (size_t si = 0; si < m.params().slice_count(); ++si) {
        const ParamSlice& sl = m.params().slice(int(si));
        // Roughness (one channel) carries table quadrature error: RoughnessGradient* tests it.
        if (sl.channels != kLatentChannels) continue;
        const float h = sl.kind == "reflectance" ? 1e-2f : 0.1f;
        for (int c : {0, 7, 15}) {
            std::vector<float> v(m.params().value(int(si)), m.params().value(int(si)) + sl.channels);
            const float v0 = v[c];
            v[c] = v0 + h;
            m.params().set_value(int(si), v.data());
            double lp = loss(m, o, w);
            v[c] = v0 - h;
            m.params().set_value(int(si), v.data());
            double lm = loss(m, o, w);
            v[c] = v0;
            m.params().set_value(int(si), v.data());
            checks.push_back(
                {sl.name + " channel " + std::to_string(c), grad[sl.value_offset + c], (lp - lm) / (2.0 * h)});
        }
    }
    m.sync();
    double largest = 0;
    for (const Check& k : checks) largest = std::max(largest, std::abs(k.fd));
    EXPECT_GT(largest, 1e-3);
    int nonzero = 0;
    std::set<std::string> exercised;
    for (const Check& k : checks) {
        EXPECT_NEAR(k.g, k.fd, tol * std::max(std::abs(k.fd), 1e-2 * largest)) << k.what;
        if (std::getenv("LPT_DEBUG_FD")) std::cerr << k.what << " " << k.g << " " << k.fd << "\n";
        if (std::abs(k.fd) > 1e-2 * largest) {
            ++nonzero;
            exercised.insert(k.what.substr(0, k.what.find(" channel")));
        }
    }
    EXPECT_GT(nonzero, int(nonzero_fraction * double(checks.size())))
        << "most derivatives are ~0: the scene does not exercise the parameters";
    return exercised;
}

/// The Cornell box with a mirror tall block and a glass short block: delta bounces before the
/// first non-delta vertex (Ĩa, Ĩc behind them) and delta coefficient gradients.
Scene cornell_with_delta_blocks() {
    Scene s = small_cornell(5);
    Props mirror;
    mirror.type = "conductor";
    mirror.file = "test";
    Props glass;
    glass.type = "dielectric";
    glass.file = "test";
    s.materials.push_back(mirror);
    s.shapes[s.find_shape("tall_block")].material = int(s.materials.size()) - 1;
    s.materials.push_back(glass);
    s.shapes[s.find_shape("short_block")].material = int(s.materials.size()) - 1;
    return s;
}

}  // namespace

TEST(LatentAdjoint, GradientsMatchFiniteDifferencesCodeParameterisation) {
    Scene scene = small_cornell();
    LatentModel m(scene, Parameterisation::Code, 1);
    check_all_slices(m, opts(scene), 1e-3);
}

TEST(LatentAdjoint, GradientsMatchFiniteDifferencesVisibleGateAndMis) {
    Scene scene = small_cornell(3);
    LatentModel m(scene, Parameterisation::Paper, 2);
    m.terms().gate = OcclusionGate::Visible;
    check_all_slices(m, opts(scene), 1e-3);
}

TEST(LatentAdjoint, GradientsMatchFiniteDifferencesThroughMirrorAndGlass) {
    Scene scene = cornell_with_delta_blocks();
    LatentModel m(scene, Parameterisation::Code, 6);
    RenderOptions o = opts(scene);
    o.spp = 16;
    check_all_slices(m, o, 1e-3);
}

TEST(LatentAdjoint, ZeroReflectanceKeepsItsGradient) {
    Scene scene = small_cornell();
    LatentModel m(scene, Parameterisation::Paper, 3);
    const int floor_refl = m.params().find("floor.bsdf.reflectance");
    ASSERT_GE(floor_refl, 0);
    std::vector<float> zero(kLatentChannels, 0.f);
    m.params().set_value(floor_refl, zero.data());
    m.sync();
    RenderOptions o = opts(scene);
    const std::vector<float> w = weights(size_t(scene.camera.width) * scene.camera.height * kLatentChannels);
    m.params().zero_grad();
    backward_latent(m, o, w);
    const ParamSlice& sl = m.params().slice(floor_refl);
    double norm = 0;
    for (int c = 0; c < kLatentChannels; ++c) norm += std::abs(m.params().grad_values()[sl.value_offset + c]);
    EXPECT_GT(norm, 1e-4) << "a reflectance at exactly 0 lost its gradient";
    check_all_slices(m, o, 1e-3);
}

TEST(LatentAdjoint, ReplayImageAndGradientsIndependentOfThreads) {
    Scene scene = small_cornell();
    LatentModel m(scene, Parameterisation::Code, 4);
    RenderOptions o = opts(scene);
    const std::vector<float> w = weights(size_t(scene.camera.width) * scene.camera.height * kLatentChannels);
    auto primal = render_latent_terms<kLatentChannels>(m.scene(), m.spectra(), m.terms(), o).sum();
    std::vector<float> g1, g2, img1;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        m.params().zero_grad();
        img1 = backward_latent(m, o, w);
        g1 = m.params().grad_values();
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
        m.params().zero_grad();
        backward_latent(m, o, w);
        g2 = m.params().grad_values();
    }
    EXPECT_EQ(img1, primal);
    EXPECT_EQ(g1, g2);
}

TEST(LatentAdjoint, RejectsWrongGradientShape) {
    Scene scene = small_cornell();
    LatentModel m(scene, Parameterisation::Code, 5);
    EXPECT_THROW(backward_latent(m, opts(scene), std::vector<float>(10)), std::invalid_argument);
}

TEST(LatentAdjoint, RoughnessGradientMatchesFiniteDifferencesInExpectation) {
    // Sampling depends on alpha, so one seed's replay gradient (sampling held fixed) and one
    // seed's finite difference (sampling moves) differ; both are unbiased for d E[loss]/d alpha.
    // Compare their means over seeds within 4 standard errors, and require the standard error to
    // be small enough (< 25% of the value) for the comparison to mean something.
    Scene scene =
        load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json", {{"camera.width", "16"},
                                                                                    {"camera.height", "16"},
                                                                                    {"integrator.max_depth", "3"},
                                                                                    {"integrator.rr_depth", "100"}});
    Props rough;
    rough.type = "roughconductor";
    rough.file = "test";
    rough.values["alpha"] = 0.3f;
    rough.values["distribution"] = std::string("ggx");
    scene.materials.push_back(rough);
    scene.shapes[scene.find_shape("tall_block")].material = int(scene.materials.size()) - 1;
    LatentModel m(scene, Parameterisation::Code, 8);
    const int alpha = m.params().find("tall_block.bsdf.alpha");
    ASSERT_GE(alpha, 0) << "roughconductor exposes no alpha";
    // Uniform weights: random signs would cancel the block's contributions and drown the signal.
    const std::vector<float> w(size_t(scene.camera.width) * scene.camera.height * kLatentChannels, 1.f);
    const float a0 = *m.params().value(alpha), h = 0.05f;
    std::vector<double> prb, fd;
    for (uint64_t seed = 0; seed < 24; ++seed) {
        RenderOptions o = opts(scene);
        o.seed = 100 + seed;
        o.spp = 32;
        m.params().zero_grad();
        backward_latent(m, o, w);
        prb.push_back(m.params().grad_values()[m.params().slice(alpha).value_offset]);
        float v = a0 + h;
        m.params().set_value(alpha, &v);
        double lp = loss(m, o, w);
        v = a0 - h;
        m.params().set_value(alpha, &v);
        double lm = loss(m, o, w);
        m.params().set_value(alpha, &a0);
        m.sync();
        fd.push_back((lp - lm) / (2 * h));
    }
    auto mean_se = [](const std::vector<double>& x) {
        double s = 0, s2 = 0;
        for (double v : x) s += v, s2 += v * v;
        double mean = s / x.size();
        return std::pair{mean, std::sqrt(std::max(0.0, s2 / x.size() - mean * mean) / (x.size() - 1))};
    };
    auto [mp, sp] = mean_se(prb);
    auto [mf, sf] = mean_se(fd);
    std::cout << "d loss / d alpha: replay " << mp << " +- " << sp << ", finite differences " << mf << " +- " << sf
              << "\n";
    EXPECT_NEAR(mp, mf, 4 * std::hypot(sp, sf));
    EXPECT_LT(std::hypot(sp, sf), 0.25 * std::abs(mf)) << "too noisy to detect a wrong derivative";
}

namespace {

/// A floor (textured diffuse) and a back wall (textured nonlinear roughplastic) under an area
/// light and an environment map (the same small image: radiance varies with direction, so the
/// latent environment's L̃e is scaled by the map's relative luminance); rectangles carry uv in
/// [0, 1]², so g(uv) varies across every pixel.
Scene textured_scene() {
    // 4 x 4 linear-RGB texture with distinct luminances (EXR: no sRGB decoding).
    Image tex{4, 4, 3, {}, {"R", "G", "B"}};
    for (int i = 0; i < 16; ++i)
        tex.data.insert(tex.data.end(),
                        {0.1f + 0.05f * float(i), 0.8f - 0.04f * float(i), 0.3f + 0.02f * float(i % 5)});
    const std::string tex_path = test::write_temp_file("latent_tex.exr", "");
    write_exr(tex_path, tex);
    const std::string json = R"({
      "integrator": { "max_depth": 3, "rr_depth": 100 },
      "camera": { "fov": 50, "width": 8, "height": 8,
                  "to_world": { "lookat": { "origin": [0, 1.2, 3.5], "target": [0, 0.4, 0], "up": [0, 1, 0] } } },
      "materials": {
        "floor": { "type": "diffuse", "reflectance": { "type": "bitmap", "filename": ")" +
                             tex_path + R"(" } },
        "wall": { "type": "roughplastic", "alpha": 0.3, "nonlinear": true,
                  "diffuse_reflectance": { "type": "bitmap", "filename": ")" +
                             tex_path + R"(", "filter_type": "nearest" } } },
      "shapes": [
        { "id": "floor", "type": "rectangle", "material": "floor", "to_world": [ { "rotate": { "axis": [1, 0, 0], "angle": -90 } }, { "scale": 1.5 } ] },
        { "id": "wall", "type": "rectangle", "material": "wall", "to_world": [ { "scale": 1.5 }, { "translate": [0, 1.5, -1.5] } ] },
        { "id": "light", "type": "rectangle", "material": { "type": "diffuse", "reflectance": 0 },
          "to_world": [ { "rotate": { "axis": [1, 0, 0], "angle": 90 } }, { "scale": 0.5 }, { "translate": [0, 2.5, 0] } ],
          "emitter": { "type": "area", "radiance": 5 } } ],
      "emitters": [ { "type": "envmap", "filename": ")" +
                             tex_path + R"(", "scale": 2 } ]
    })";
    return load_scene(test::write_temp_file("textured.json", json));
}

}  // namespace

// Textured latent colours ρ = g(uv)·s + o: the scale and offset slices exist in place of the
// plain colour, and their path-replay gradients (and the environment map's L̃e) (diffuse, and nonlinear roughplastic
// whose ∂ρ̃/∂ρ depends on the hit's ρ) match central differences like every other parameter.
TEST(LatentAdjoint, TextureAndEnvMapGradientsMatchFiniteDifferences) {
    Scene scene = textured_scene();
    LatentModel m(scene, Parameterisation::Code, 4);
    std::vector<std::string> names;
    for (size_t i = 0; i < m.params().slice_count(); ++i) names.push_back(m.params().slice(int(i)).name);
    for (const char* want :
         {"floor.bsdf.reflectance.scale", "floor.bsdf.reflectance.offset", "wall.bsdf.diffuse_reflectance.scale",
          "wall.bsdf.diffuse_reflectance.offset", "wall.bsdf.specular_reflectance"})
        EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
    EXPECT_EQ(std::find(names.begin(), names.end(), "floor.bsdf.reflectance"), names.end());
    // A bright light (Code init is U[-0.1, 0.1]) so reflected light is not lost next to L̃a.
    for (size_t i = 0; i < m.params().slice_count(); ++i)
        if (m.params().slice(int(i)).name == "light.Le") {
            std::vector<float> le(kLatentChannels);
            for (int c = 0; c < kLatentChannels; ++c) le[c] = 3.f + 0.2f * float(c % 5) - (c % 3 == 0 ? 6.f : 0.f);
            m.params().set_value(int(i), le.data());
        }
    m.sync();
    RenderOptions o = opts(scene);
    o.spp = 8;
    // The light is out of view (its L̃a, L̃c, colour have no effect): judge the texture slices.
    const std::set<std::string> exercised = check_all_slices(m, o, 1e-3, 0.25);
    for (const char* want :
         {"floor.bsdf.reflectance.scale", "floor.bsdf.reflectance.offset", "wall.bsdf.diffuse_reflectance.scale",
          "wall.bsdf.diffuse_reflectance.offset", "environment.Le"})
        EXPECT_TRUE(exercised.count(want)) << want << " has only ~0 derivatives";
}

// A camera behind the Cornell box's back wall, made one-sided: every pixel sees the wall's back,
// which scores the background (RGB sees black there, like the void). The replayed gradient
// follows: the background's, matching central differences, and none for the wall's own vectors.
TEST(LatentAdjoint, TheBackOfAOneSidedWallReplaysAsTheBackground) {
    Scene scene = small_cornell();
    Props one_sided;
    one_sided.type = "diffuse";
    one_sided.file = "test";
    scene.materials.push_back(one_sided);
    scene.shapes[scene.find_shape("back")].material = int(scene.materials.size()) - 1;
    scene.camera.world_from_camera =
        Transform::look_at(Vec3f(2.78f, 2.73f, 9.f), Vec3f(2.78f, 2.73f, 0.f), Vec3f(0, 1, 0));
    scene.camera.fov = 5.f;
    LatentModel m(scene, Parameterisation::Code, 4);
    const std::set<std::string> exercised = check_all_slices(m, opts(scene), 1e-3, 0.0);
    EXPECT_EQ(exercised, std::set<std::string>{"background"});
}
