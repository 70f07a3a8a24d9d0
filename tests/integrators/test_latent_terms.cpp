// Latent terms Ĩe, Ĩa, Ĩc: linearity in L̃e/L̃a/L̃c (exact, same random numbers), analytic values
// on a plane under a light, the occlusion gate both ways, the background, and Ĩe == the plain
// path tracer.
#include "integrators/path.h"
#include "scene_fixtures.h"
#include <gtest/gtest.h>

using namespace lpt;

namespace {

using S16 = Spectrum<16>;

S16 ramp(float a, float b) {
    S16 s;
    for (int c = 0; c < 16; ++c) s[c] = a + b * float(c) / 15.f;
    return s;
}

LatentTerms<16> zero_terms(const Scene& scene) {
    LatentTerms<16> t;
    t.La.assign(scene.shapes.size(), S16::Zero());
    t.Lc.assign(scene.shapes.size(), S16::Zero());
    return t;
}

RenderOptions options(const Scene& scene, int spp = 4) {
    RenderOptions o = RenderOptions::from_scene(scene);
    o.spp = spp;
    o.seed = 9;
    return o;
}

float max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
    float m = 0;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
    return m;
}

float max_abs(const std::vector<float>& a) {
    float m = 0;
    for (float v : a) m = std::max(m, std::abs(v));
    return m;
}

}  // namespace

TEST(LatentTerms, EachTermIsLinearInItsVector) {
    Scene scene = load_scene(test::cornell_box_path(), {{"camera.width", "12"}, {"camera.height", "12"}});
    auto spectra = SceneSpectra<16>::from_description(scene);
    const S16 v1 = ramp(-0.7f, 1.3f), v2 = ramp(0.4f, -0.9f);
    const int light = scene.shapes[scene.find_shape("light")].emitter;
    auto render = [&](const S16& le, const S16& la, const S16& lc) {
        auto sp = SceneSpectra<16>::from_description(scene);
        sp.radiance[light] = le;
        LatentTerms<16> t = zero_terms(scene);
        for (auto& x : t.La) x = la;
        for (auto& x : t.Lc) x = lc;
        return render_latent_terms<16>(scene, sp, t, options(scene));
    };
    const S16 z = S16::Zero();
    auto f1 = render(v1, v1, v1), f2 = render(v2, v2, v2), f12 = render(v1 + v2, v1 + v2, v1 + v2);
    auto check = [&](const Film<16>& a, const Film<16>& b, const Film<16>& ab, const char* term) {
        std::vector<float> sa = a.develop(), sb = b.develop(), sab = ab.develop();
        for (size_t i = 0; i < sa.size(); ++i) sa[i] += sb[i];
        EXPECT_LT(max_abs_diff(sa, sab), 1e-5f * (1.f + max_abs(sab))) << term;
        EXPECT_GT(max_abs(sab), 1e-3f) << term << " is identically zero: the test would prove nothing";
    };
    check(f1.e, f2.e, f12.e, "Ie");
    check(f1.a, f2.a, f12.a, "Ia");
    check(f1.c, f2.c, f12.c, "Ic");
    (void)z;
}

TEST(LatentTerms, EmissionTermIsThePlainPathTracer) {
    Scene scene = load_scene(test::cornell_box_path(), {{"camera.width", "10"}, {"camera.height", "10"}});
    auto spectra = SceneSpectra<16>::from_description(scene);
    auto films = render_latent_terms<16>(scene, spectra, zero_terms(scene), options(scene));
    auto plain = render_path<16>(scene, spectra, options(scene)).develop();
    EXPECT_EQ(films.e.develop(), plain);
    EXPECT_EQ(max_abs(films.a.develop()), 0.f);
    EXPECT_EQ(max_abs(films.c.develop()), 0.f);
}

TEST(LatentTerms, AmbientIsLaAtTheFirstDiffuseVertex) {
    // Every pixel sees the diffuse plane directly: Ĩa = β · L̃a = L̃a exactly.
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
    auto spectra = SceneSpectra<16>::from_description(scene);
    LatentTerms<16> t = zero_terms(scene);
    const S16 la = ramp(-0.3f, 0.8f);
    t.La[scene.find_shape("plane")] = la;
    t.La[scene.find_shape("light")] = ramp(5.f, 1.f);  // never the first vertex here
    t.emission = false;
    auto img = render_latent_terms<16>(scene, spectra, t, options(scene)).a.develop();
    for (size_t i = 0; i < img.size(); ++i) EXPECT_NEAR(img[i], la[int(i % 16)], 1e-6f);
}

TEST(LatentTerms, BackgroundForEscapingCameraRays) {
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
    scene.camera.world_from_camera =
        Transform::look_at(Vec3f(5, 5, 5), Vec3f(10, 10, 10), Vec3f(0, 0, 1));  // looks at the sky
    auto spectra = SceneSpectra<16>::from_description(scene);
    LatentTerms<16> t = zero_terms(scene);
    t.background = ramp(0.2f, -0.6f);
    auto img = render_latent_terms<16>(scene, spectra, t, options(scene)).a.develop();
    for (size_t i = 0; i < img.size(); ++i) EXPECT_NEAR(img[i], t.background[int(i % 16)], 1e-6f);
}

TEST(LatentTerms, OcclusionGateBothWays) {
    // Plane under a light, no occluder: every light sample is visible. Then a blocker between.
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
    const S16 lc = ramp(0.5f, -1.f);
    auto gate_images = [&](const Scene& sc) {
        auto spectra = SceneSpectra<16>::from_description(sc);
        LatentTerms<16> t = zero_terms(sc);
        t.Lc[sc.find_shape("plane")] = lc;
        t.gate = OcclusionGate::Shadowed;
        auto shadowed = render_latent_terms<16>(sc, spectra, t, options(sc)).c.develop();
        t.gate = OcclusionGate::Visible;
        auto visible = render_latent_terms<16>(sc, spectra, t, options(sc)).c.develop();
        return std::pair{shadowed, visible};
    };
    auto [sh_open, vis_open] = gate_images(scene);
    for (size_t i = 0; i < sh_open.size(); ++i) {
        EXPECT_NEAR(sh_open[i], 0.f, 1e-6f);
        EXPECT_NEAR(vis_open[i], lc[int(i % 16)], 1e-6f);
    }
    Shape blocker;
    blocker.id = "blocker";
    blocker.mesh = make_rectangle();
    blocker.mesh.transform(Transform::translate(Vec3f(0, 0, 0.75f)) * Transform::scale(Vec3f(5, 5, 1)));
    blocker.material = scene.shapes[scene.find_shape("light")].material;
    scene.shapes.push_back(std::move(blocker));
    scene.build();
    auto [sh_blocked, vis_blocked] = gate_images(scene);
    for (size_t i = 0; i < sh_blocked.size(); ++i) {
        EXPECT_NEAR(sh_blocked[i], lc[int(i % 16)], 1e-6f);
        EXPECT_NEAR(vis_blocked[i], 0.f, 1e-6f);
    }
}

TEST(LatentTerms, TheBackOfAOneSidedSurfaceShowsTheBackground) {
    // Seen from below, the one-sided plane is black in RGB, like the void: Ĩa = background and
    // Ĩc = 0 exactly, not its lit side's L̃a / L̃c. Wrapped in twosided it shows L̃a again.
    auto images = [](bool two_sided) {
        Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
        if (two_sided) {
            Props wrap;
            wrap.type = "twosided";
            wrap.file = "test";
            wrap.values["bsdf"] = std::make_shared<Props>(scene.materials[scene.shapes[0].material]);
            scene.materials.push_back(wrap);
            scene.shapes[scene.find_shape("plane")].material = int(scene.materials.size()) - 1;
        }
        scene.camera.world_from_camera = Transform::look_at(Vec3f(0, 0, -0.5f), Vec3f(0, 0, 0), Vec3f(0, 1, 0));
        auto spectra = SceneSpectra<16>::from_description(scene);
        LatentTerms<16> t = zero_terms(scene);
        t.La[scene.find_shape("plane")] = ramp(-0.3f, 0.8f);
        t.Lc[scene.find_shape("plane")] = ramp(0.9f, -0.4f);
        t.background = ramp(0.2f, -0.6f);
        auto films = render_latent_terms<16>(scene, spectra, t, options(scene));
        return std::tuple{films.a.develop(), films.c.develop(), t};
    };
    auto [a1, c1, t1] = images(false);
    for (size_t i = 0; i < a1.size(); ++i) {
        EXPECT_NEAR(a1[i], t1.background[int(i % 16)], 1e-6f);
        EXPECT_EQ(c1[i], 0.f);
    }
    auto [a2, c2, t2] = images(true);
    const S16 la = t2.La[test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f).find_shape("plane")];
    for (size_t i = 0; i < a2.size(); ++i) EXPECT_NEAR(a2[i], la[int(i % 16)], 1e-6f);
    EXPECT_GT(max_abs(c2), 0.1f) << "the plane shadows itself from below: Ĩc must count there";
}

// Edits of what the training view never showed (LatentTerms::looks): camera rays that hit
// nothing, or the emitting side of a shape given a look, score that look into Ĩa and nothing
// else (no environment L̃e, no b̃, no emission); every other pixel renders exactly as before.
namespace {

/// Looking straight at the edge (x = 100) of a plane that emits upwards from `camera_z` above it
/// (below: its back, one-sided diffuse): half of the pixels see the plane, the others nothing but
/// the constant environment.
Scene plane_edge_scene(float camera_z) {
    const std::string json = R"({
      "integrator": {"max_depth": 3, "rr_depth": 100},
      "camera": {"fov": 20, "width": 8, "height": 8, "filter": {"type": "box"}, "near_clip": 1e-4,
                 "to_world": {"lookat": {"origin": [100, 0, )" +
                             std::to_string(camera_z) +
                             R"(], "target": [100, 0, 0], "up": [0, 1, 0]}}},
      "materials": {"plane": {"type": "diffuse", "reflectance": 0.5}},
      "shapes": [{"id": "plane", "type": "rectangle", "material": "plane", "to_world": {"scale": [100, 100, 1]},
                  "emitter": {"type": "area", "radiance": 3}}],
      "emitters": [{"type": "constant", "radiance": 2}]
    })";
    return load_scene(test::write_temp_file(camera_z > 0 ? "plane_edge.json" : "plane_edge_below.json", json));
}

}  // namespace

TEST(LatentTerms, CameraRaysScoreTheLooksEditsGive) {
    const Scene scene = plane_edge_scene(1.f);
    auto spectra = SceneSpectra<16>::from_description(scene);
    const int plane = scene.find_shape("plane");
    LatentTerms<16> t = zero_terms(scene);
    const S16 la = ramp(-0.3f, 0.8f), v_nothing = ramp(1.5f, -2.f), v_plane = ramp(-1.f, 0.5f);
    t.La[plane] = la;
    t.background = ramp(0.2f, -0.6f);
    const TermFilms<16> before = render_latent_terms<16>(scene, spectra, t, options(scene));
    for (const bool plane_look : {false, true}) {
        LatentTerms<16> u = t;
        u.looks = {v_nothing, v_plane};
        u.look_of_nothing = 0;
        if (plane_look) {  // else look_of_shape stays empty: no shape has a look
            u.look_of_shape.assign(scene.shapes.size(), -1);
            u.look_of_shape[plane] = 1;
        }
        const TermFilms<16> after = render_latent_terms<16>(scene, spectra, u, options(scene));
        const std::vector<float> e0 = before.e.develop(), a0 = before.a.develop(), c0 = before.c.develop();
        const std::vector<float> e1 = after.e.develop(), a1 = after.a.develop(), c1 = after.c.develop();
        const S16 env = spectra.radiance[scene.environment];
        int surface = 0, nothing = 0;
        for (size_t p = 0; p < e0.size() / 16; ++p) {
            const bool missed = std::abs(a0[p * 16] - t.background[0]) < 1e-6f;  // la[0] = −0.3, b̃[0] = 0.2
            surface += !missed;
            nothing += missed;
            for (int k = 0; k < 16; ++k) {
                const size_t i = p * 16 + k;
                if (missed) {
                    EXPECT_NEAR(e0[i], env[k], 1e-6f) << "before: the environment, seen directly";
                }
                if (missed || plane_look) {
                    EXPECT_NEAR(a1[i], (missed ? v_nothing : v_plane)[k], 1e-6f) << p;
                    EXPECT_EQ(e1[i], 0.f) << p;
                    EXPECT_EQ(c1[i], 0.f) << p;
                } else {
                    EXPECT_EQ(e1[i], e0[i]) << p;
                    EXPECT_EQ(a1[i], a0[i]) << p;
                    EXPECT_EQ(c1[i], c0[i]) << p;
                }
            }
        }
        EXPECT_EQ(surface, 32);
        EXPECT_EQ(nothing, 32);
    }
}

// From below, the same edge shows the plane's back, where a one-sided diffuse scatters nothing:
// RGB renders it black, and before looks it scores b̃ as the void beside it does. Given looks for
// nothing and for black, each scores its own, and nothing else.
TEST(LatentTerms, CameraRaysMeetingABlackBackScoreTheLookOfBlack) {
    const Scene scene = plane_edge_scene(-1.f);
    auto spectra = SceneSpectra<16>::from_description(scene);
    const int plane = scene.find_shape("plane");
    LatentTerms<16> t = zero_terms(scene);
    t.La[plane] = ramp(-0.3f, 0.8f);
    t.Lc[plane] = ramp(0.4f, 0.3f);
    t.background = ramp(0.2f, -0.6f);
    const S16 v_nothing = ramp(1.5f, -2.f), v_black = ramp(-0.8f, 1.1f);
    LatentTerms<16> u = t;
    u.looks = {v_nothing, v_black};
    u.look_of_nothing = 0;
    u.look_of_black = 1;
    const TermFilms<16> before = render_latent_terms<16>(scene, spectra, t, options(scene));
    const TermFilms<16> after = render_latent_terms<16>(scene, spectra, u, options(scene));
    const std::vector<float> e0 = before.e.develop(), a0 = before.a.develop();
    const std::vector<float> e1 = after.e.develop(), a1 = after.a.develop(), c1 = after.c.develop();
    const S16 env = spectra.radiance[scene.environment];
    int back = 0, nothing = 0;
    for (size_t p = 0; p < e0.size() / 16; ++p) {
        const bool missed = std::abs(e0[p * 16] - env[0]) < 1e-6f;  // the back emits nothing
        back += !missed;
        nothing += missed;
        for (int k = 0; k < 16; ++k) {
            const size_t i = p * 16 + k;
            EXPECT_NEAR(a0[i], t.background[k], 1e-6f) << "before: the back, as the void, scores b̃ " << p;
            if (!missed) EXPECT_NEAR(e0[i], 0.f, 1e-6f) << p;
            EXPECT_NEAR(a1[i], (missed ? v_nothing : v_black)[k], 1e-6f) << p;
            EXPECT_EQ(e1[i], 0.f) << p;
            EXPECT_EQ(c1[i], 0.f) << p;
        }
    }
    EXPECT_EQ(back, 32);
    EXPECT_EQ(nothing, 32);
}

// A look index that names no look is the caller's error: the render refuses it before tracing
// rather than quietly scoring the fitted terms where the look was meant to show.
TEST(LatentTerms, LookIndicesThatNameNoLookAreRefused) {
    const Scene scene = plane_edge_scene(-1.f);
    auto spectra = SceneSpectra<16>::from_description(scene);
    const LatentTerms<16> t = zero_terms(scene);
    const S16 v = ramp(1.5f, -2.f);
    auto render = [&](const LatentTerms<16>& u) { return render_latent_terms<16>(scene, spectra, u, options(scene)); };
    LatentTerms<16> black = t;
    black.looks = {v};
    black.look_of_black = 1;
    EXPECT_THROW(render(black), std::invalid_argument);
    LatentTerms<16> nothing = t;  // no looks at all, yet an index
    nothing.look_of_nothing = 0;
    EXPECT_THROW(render(nothing), std::invalid_argument);
    LatentTerms<16> shape = t;
    shape.looks = {v};
    shape.look_of_shape.assign(scene.shapes.size(), -2);
    EXPECT_THROW(render(shape), std::invalid_argument);
    shape.look_of_shape.assign(scene.shapes.size(), 0);
    EXPECT_NO_THROW(render(shape));
}
