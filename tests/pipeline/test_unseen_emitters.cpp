// Emitters the training view does not show (pipeline/unseen_emitters.h): a second light hidden
// behind the box's back wall and moved into view by an edit. The frame's latent is the flat
// colour's latent where the light covers whole pixels and the render without looks wherever it
// is not seen, and that latent decodes to the light's display colour; the box's own light,
// which training sees, keeps its fitted look.
#include "autodiff/fit.h"
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "integrators/aov.h"
#include "pipeline/edit_session.h"
#include "pipeline/fit.h"
#include "pipeline/unseen_emitters.h"
#include "pipeline/vae_source.h"
#include "test_util.h"
#include "vae/vae.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>

using namespace lpt;

namespace {

const std::string kBox = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json";

/// The box with a second light, a quad 0.9 units behind the back wall (hidden) facing the camera;
/// or, `turned_away`, 0.6 units before it, facing the wall: in view, its back to the camera.
std::string box_with_a_hidden_light(const std::string& dir, bool turned_away = false) {
    std::string text = read_file(kBox);
    const std::string light = R"({ "id": "light", "type": "mesh", "material": "light", "to_world": { "scale": 0.01 },)";
    const size_t at = text.find(light);
    if (at == std::string::npos) throw std::runtime_error("the box's light entry moved: update this test");
    const std::string hidden =
        std::string(R"({ "id": "hidden_light", "type": "mesh", "material": "light", "to_world": { "scale": 0.01 },
      "positions": )") +
        (turned_away ? "[[400, 350, 500], [400, 520, 500], [150, 520, 500], [150, 350, 500]]"
                     : "[[400, 350, 650], [150, 350, 650], [150, 520, 650], [400, 520, 650]]") +
        R"(, "indices": [[0, 1, 2, 3]],
      "emitter": { "type": "area", "radiance": [17, 12, 4] } },
    )";
    text.insert(at, hidden);
    const std::string path = dir + "/scene.json";
    write_text_atomic(path, text);
    return path;
}

int shape_index(const Scene& scene, const std::string& id) {
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (scene.shapes[i].id == id) return int(i);
    return -1;
}

/// A 16² latent fit of `scene` in dir/fit, 5 iterations at 2 spp, no refiner, with `defines`.
pipeline::FitJob small_fit(const std::string& scene, std::map<std::string, std::string> defines,
                           const std::string& dir) {
    pipeline::FitJob job;
    job.scene = scene;
    defines["integrator.max_depth"] = "3";
    job.defines = defines;
    job.out = dir + "/fit";
    job.synthetic_res = "16x16";
    job.options.iterations = 5;
    job.options.spp = 2;
    job.final_spp = 2;
    job.refiner = false;
    pipeline::run_fit(job);
    return job;
}

/// The fit's latent of its scene as it stands, as render_fit_latent renders it but without the
/// looks an EditSession gives its terms.
std::vector<float> without_looks(const pipeline::FitFolder& fit, int w, int h, int spp, uint64_t seed) {
    LatentTerms<kLatentChannels> terms = fit.model->terms();
    terms.looks.clear();  // and every index into them, which a render checks
    terms.look_of_shape.clear();
    terms.look_of_nothing = terms.look_of_black = -1;
    const RenderOptions options = RenderOptions::from_scene(*fit.scene, w, h, spp, seed);
    return toned_sum(render_latent_terms<kLatentChannels>(*fit.scene, fit.model->spectra(), terms, options), fit.tone);
}

/// Black backs take black's look: the VAE's latent of a flat black image.
void expect_blacks_look(const pipeline::FitFolder& fit, const pipeline::UnseenEmitters& unseen) {
    ASSERT_TRUE(unseen.black().has_value());
    const std::unique_ptr<Vae> vae = pipeline::open_vae(fit.vae);
    const float black[3] = {0.f, 0.f, 0.f};
    EXPECT_EQ(*unseen.black(), pipeline::flat_colour_latent(*vae, black));
}

}  // namespace

TEST(UnseenEmitters, ShapeCoverageIsTheEmitterCellsOfTheOnlyEmitter) {
    const Scene scene = load_scene(kBox);
    const int light = shape_index(scene, "light");
    ASSERT_GE(light, 0);
    const std::vector<float> mine = render_shape_coverage(scene, 16, 12, {light}, 4);
    EXPECT_EQ(mine, render_emitter_cells(scene, 16, 12, 1, 4));
    float covered = 0.f;
    for (float c : mine) covered += c;
    EXPECT_GT(covered, 1.f) << "the light is in view";
}

TEST(UnseenEmitters, AHiddenLightBroughtIntoViewLooksLikeItsColour) {
    if (!pipeline::vae_present({})) GTEST_SKIP() << "no TAESD3 weights in ../shared";
    const std::string dir = test::temp_dir("unseen-emitters");
    // a box filter: a pixel's samples stay inside it, so whole pixels show nothing but the light
    const pipeline::FitJob job = small_fit(box_with_a_hidden_light(dir), {{"camera.filter.type", "box"}}, dir);
    const std::string edits = test::write_temp_file(
        "lower.json",
        R"({ "frames": 2, "shapes": [ { "id": "hidden_light", "translate": [[0, 0, 0], [0, 0, -3]] } ] })");
    pipeline::EditSession session(job.out, edits);
    const pipeline::UnseenEmitters& unseen = session.unseen_emitters();
    const int hidden = shape_index(*session.fit().scene, "hidden_light");
    ASSERT_EQ(unseen.shapes(), std::vector<int>{hidden}) << "the box's own light is seen in training";
    // edited frames' keys name what has a look (the view shows the void, and no black back)
    EXPECT_EQ(unseen.key(), "shape " + std::to_string(hidden) + " black backs");

    const pipeline::FrameLatents f = session.frame(1, 2, 0);  // moved by 1.5: in front of the back wall
    const std::vector<float> cover = render_shape_coverage(*session.fit().scene, 16, 16, {hidden});
    const std::vector<float> raw = without_looks(session.fit(), 16, 16, 2, 1);  // seed + frame
    const std::unique_ptr<Vae> vae = pipeline::open_vae(session.fit().vae);
    const float white[3] = {1.f, 1.f, 1.f};  // radiance (17, 12, 4) clipped
    const std::vector<float> look = pipeline::flat_colour_latent(*vae, white);
    int whole = 0, unseen_pixels = 0;
    for (size_t p = 0; p < cover.size(); ++p)
        for (int k = 0; k < 16; ++k) {
            const float got = f.latent[p * 16 + k];
            if (cover[p] == 1.f) {
                EXPECT_NEAR(got, look[k], 1e-4f) << p;  // through the tone curve and back
            }
            if (cover[p] == 0.f) {
                EXPECT_EQ(got, raw[p * 16 + k]) << p;
            }
            whole += k == 0 && cover[p] == 1.f;
            unseen_pixels += k == 0 && cover[p] == 0.f;
        }
    EXPECT_GE(whole, 2) << "the moved light covers whole latent pixels";
    EXPECT_GE(unseen_pixels, 200);
    const std::vector<float> training = session.frame(0, 2, 0).latent;  // the scene back at rest, first
    EXPECT_EQ(training, pipeline::render_fit_latent(session.fit(), 16, 16, 2, 0)) << "rendered without looks";
    // The latent, tiled, decodes to white: it is the light's look, not the fit's L̃e.
    std::vector<float> tiled;
    for (int p = 0; p < 16 * 16; ++p) tiled.insert(tiled.end(), look.begin(), look.end());
    const std::vector<float> rgb = vae->decode(tiled, 16, 16);
    const size_t centre = (size_t(64) * 128 + 64) * 3;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(rgb[centre + k], 1.f, 0.08f) << k;
}

// The environment the training view does not show: the bundled box, narrowed to fill its view,
// and the camera panned past its walls. Latent pixels that see nothing but the void take the
// latent of black (no environment), through the tone curve; the training view is the fit's own
// render bit for bit.
TEST(UnseenEmitters, ACameraPannedPastTheWallsSeesTheVoidAsBlack) {
    if (!pipeline::vae_present({})) GTEST_SKIP() << "no TAESD3 weights in ../shared";
    const std::string dir = test::temp_dir("unseen-environment");
    const pipeline::FitJob job = small_fit(kBox, {{"camera.fov", "25"}}, dir);  // the box fills the view
    const std::string edits = test::write_temp_file(
        "pan.json", R"({ "frames": 2, "camera": { "orbit": { "azimuth": [0, 40], "pivot": [2.78, 2.73, -8] } } })");
    pipeline::EditSession session(job.out, edits);
    ASSERT_TRUE(session.unseen_emitters().environment_unseen()) << "the box fills its training view";
    const std::string key = session.unseen_emitters().key();  // (at 25° the box's light is out of view too)
    EXPECT_EQ(key.substr(key.find("the environment")), "the environment black backs") << key;
    const std::vector<float> training = session.frame(0, 2, 0).latent;  // the scene at rest, first
    EXPECT_EQ(training, pipeline::render_fit_latent(session.fit(), 16, 16, 2, 0));

    const pipeline::FrameLatents f = session.frame(1, 2, 0);  // panned by 20°: the box's right half, then nothing
    const std::vector<float> nothing = render_shape_coverage(*session.fit().scene, 16, 16, {-1});
    const std::unique_ptr<Vae> vae = pipeline::open_vae(session.fit().vae);
    const float black[3] = {0.f, 0.f, 0.f};
    const std::vector<float> look = pipeline::flat_colour_latent(*vae, black);
    int void_pixels = 0, seen_pixels = 0;
    for (size_t p = 0; p < nothing.size(); ++p) {
        if (nothing[p] < 1.f) {
            seen_pixels += nothing[p] == 0.f;
            continue;
        }
        ++void_pixels;
        for (int k = 0; k < 16; ++k) EXPECT_NEAR(f.latent[p * 16 + k], look[k], 1e-4f) << p << " " << k;
    }
    EXPECT_GE(void_pixels, 16) << "the orbit looks past the box";
    EXPECT_GE(seen_pixels, 16);
}

// -D overrides at edit time may widen the view past the walls. What the training view showed is
// still judged on the scene as fitted (the void unseen), and with overrides no frame is the
// training view, so frame 0 shows the void in its look too.
TEST(UnseenEmitters, OverridesThatWidenTheViewKeepTheTrainingViewsVerdict) {
    if (!pipeline::vae_present({})) GTEST_SKIP() << "no TAESD3 weights in ../shared";
    const std::string dir = test::temp_dir("unseen-overridden");
    const pipeline::FitJob job = small_fit(kBox, {{"camera.fov", "25"}}, dir);  // the box fills the view
    const std::string edits = test::write_temp_file("still.json", R"({ "frames": 1 })");
    pipeline::EditSession session(job.out, edits, {{"camera.fov", "70"}});
    ASSERT_TRUE(session.unseen_emitters().environment_unseen()) << "judged on the view as fitted";
    const pipeline::FrameLatents f = session.frame(0, 2, 0);
    const std::vector<float> nothing = render_shape_coverage(*session.fit().scene, 16, 16, {-1});
    const std::unique_ptr<Vae> vae = pipeline::open_vae(session.fit().vae);
    const float black[3] = {0.f, 0.f, 0.f};
    const std::vector<float> look = pipeline::flat_colour_latent(*vae, black);
    // the camera's tent filter reaches a pixel beyond each pixel: a pixel and its neighbours see nothing
    auto all_void_around = [&](int x, int y) {
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int u = std::clamp(x + dx, 0, 15), v = std::clamp(y + dy, 0, 15);
                if (nothing[size_t(v) * 16 + u] < 1.f) return false;
            }
        return true;
    };
    int void_pixels = 0;
    for (size_t p = 0; p < nothing.size(); ++p) {
        if (!all_void_around(int(p % 16), int(p / 16))) continue;
        ++void_pixels;
        for (int k = 0; k < 16; ++k) EXPECT_NEAR(f.latent[p * 16 + k], look[k], 1e-4f) << p << " " << k;
    }
    EXPECT_GE(void_pixels, 16) << "the wider view looks past the box";
}

// Where the environment is unseen, the black backs of one-sided surfaces take black's latent,
// not the environment's: the box, narrowed to fill its view, under a grey sky.
TEST(UnseenEmitters, BlackBacksTakeBlacksLookNotTheSkys) {
    if (!pipeline::vae_present({})) GTEST_SKIP() << "no TAESD3 weights in ../shared";
    const std::string dir = test::temp_dir("unseen-sky");
    std::string text = read_file(kBox);
    const size_t at = text.find("\"shapes\":");
    ASSERT_NE(at, std::string::npos) << "the box's shapes entry moved: update this test";
    text.insert(at, R"("emitters": [{ "type": "constant", "radiance": 0.2 }],
  )");
    const std::string scene = dir + "/scene.json";
    write_text_atomic(scene, text);
    const pipeline::FitJob job = small_fit(scene, {{"camera.fov", "25"}}, dir);
    const pipeline::FitFolder fit = pipeline::load_fit_folder(job.out);
    const pipeline::UnseenEmitters unseen(fit);
    ASSERT_TRUE(unseen.environment_unseen());
    ASSERT_NO_FATAL_FAILURE(expect_blacks_look(fit, unseen));
    LatentTerms<kLatentChannels> terms;
    unseen.show(terms, fit.tone, fit.scene->shapes.size(), true);
    ASSERT_GE(terms.look_of_black, 0);
    ASSERT_GE(terms.look_of_nothing, 0);
    float apart = 0.f;  // the sky's look is another latent
    for (int k = 0; k < kLatentChannels; ++k)
        apart = std::max(apart, std::abs(terms.looks[size_t(terms.look_of_black)][k] -
                                         terms.looks[size_t(terms.look_of_nothing)][k]));
    EXPECT_GT(apart, 0.1f);
    unseen.show(terms, fit.tone, fit.scene->shapes.size(), false);
    EXPECT_EQ(terms.look_of_black, -1);
}

// An emitter the training view shows only from behind was never fitted as it looks: it is unseen,
// and the training view has met a black back (the light's), so b̃ was fitted to one and stays.
TEST(UnseenEmitters, AnEmitterSeenOnlyFromBehindIsUnseen) {
    if (!pipeline::vae_present({})) GTEST_SKIP() << "no TAESD3 weights in ../shared";
    const std::string dir = test::temp_dir("unseen-behind");
    const pipeline::FitJob job = small_fit(box_with_a_hidden_light(dir, true), {}, dir);
    const pipeline::FitFolder fit = pipeline::load_fit_folder(job.out);
    const int turned = shape_index(*fit.scene, "hidden_light");
    ASSERT_GE(turned, 0);
    const std::vector<float> cover = render_shape_coverage(*fit.scene, 16, 16, {turned});
    ASSERT_GT(*std::max_element(cover.begin(), cover.end()), 0.5f) << "in view, from behind";
    const pipeline::UnseenEmitters unseen(fit);
    EXPECT_EQ(unseen.shapes(), std::vector<int>{turned}) << "the box's own light is seen from the front";
    EXPECT_FALSE(unseen.environment_unseen()) << "the bundled box's view shows the void";
    EXPECT_FALSE(unseen.black().has_value()) << "the light's back is a black back the training view shows";
    EXPECT_EQ(unseen.key(), "shape " + std::to_string(turned)) << "another set, another key";
}

// Black backs take black's look whatever the environment: the bundled box's view shows the void
// (so the environment keeps b̃) but no black back.
TEST(UnseenEmitters, BlackBacksTakeBlacksLookWhereTheViewShowsTheVoid) {
    if (!pipeline::vae_present({})) GTEST_SKIP() << "no TAESD3 weights in ../shared";
    const std::string dir = test::temp_dir("unseen-backs");
    const pipeline::FitJob job = small_fit(kBox, {}, dir);
    const pipeline::FitFolder fit = pipeline::load_fit_folder(job.out);
    const pipeline::UnseenEmitters unseen(fit);
    EXPECT_TRUE(unseen.empty());
    EXPECT_FALSE(unseen.environment_unseen());
    ASSERT_NO_FATAL_FAILURE(expect_blacks_look(fit, unseen));
    LatentTerms<kLatentChannels> terms;
    unseen.show(terms, fit.tone, fit.scene->shapes.size(), true);
    EXPECT_EQ(terms.look_of_nothing, -1);
    ASSERT_EQ(terms.look_of_black, 0);
    EXPECT_EQ(terms.looks.size(), 1u);
    EXPECT_EQ(unseen.key(), "black backs");
}
