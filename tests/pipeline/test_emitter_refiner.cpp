// The emitter refiner (pipeline/emitter_refiner.h): its mask covers the pixels where an emitter is
// seen otherwise than in training and the square around them, its output replaces the main
// refiner's exactly there in every edited frame, the training view keeps the main refiner's
// output, and a folder that cannot have one is an error naming the file.
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "pipeline/edit_session.h"
#include "pipeline/emitter_refiner.h"
#include "pipeline/fit.h"
#include "pipeline/refine.h"
#include "pipeline/refiner_io.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <cstdlib>
#include <filesystem>

using namespace lpt;
namespace fs = std::filesystem;

namespace {

const std::string kBox = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json";

/// A small fit of the bundled box in <dir>/fit, with a main refiner of two steps when `refiner`.
std::string small_fit(const std::string& dir, bool refiner = true) {
    pipeline::FitJob job;
    job.scene = kBox;
    job.defines = {{"integrator.max_depth", "3"}};
    job.out = dir + "/fit";
    job.synthetic_res = "16x16";
    job.options.iterations = 10;
    job.options.spp = 2;
    job.final_spp = 4;
    job.refiner = refiner;
    job.refine.net.expansion = 1;
    job.refine.train.iterations = 2;
    pipeline::run_fit(job);
    return job.out;
}

pipeline::RefineJob emitter_job(const std::string& fitdir) {
    pipeline::RefineJob r;
    r.fitdir = fitdir;
    r.emitters = true;
    r.net.expansion = 2;
    r.train.iterations = 3;
    r.train.seed = 7;
    return r;
}

}  // namespace

TEST(EmitterRefiner, DilationTakesTheSquareAroundEachPixel) {
    const int w = 9, h = 7;
    std::vector<float> mask(w * h, 0.f);
    mask[3 * w + 4] = 1.f;  // (4, 3)
    mask[0] = 1.f;          // (0, 0): the square is cut by the edges
    const std::vector<float> out = pipeline::dilate_mask(mask, w, h, 2);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const bool near_centre = std::abs(x - 4) <= 2 && std::abs(y - 3) <= 2;
            const bool near_corner = x <= 2 && y <= 2;
            EXPECT_EQ(out[y * w + x], near_centre || near_corner ? 1.f : 0.f) << x << "," << y;
        }
    EXPECT_EQ(pipeline::dilate_mask(mask, w, h, 0), mask);
}

// Without a training view to compare with (another size), the mask is where the light is seen.
// Independent of render_emitter_cells: every pixel whose centre sees the light is in the mask,
// and every pixel of the undilated mask is next to one (the box's light is wider than a pixel).
TEST(EmitterRefiner, MaskCoversThePixelsTheLightIsSeenIn) {
    const Scene scene = load_scene(kBox);
    const int w = 24, h = 24;
    const Camera camera = scene.camera.with_resolution(w, h);
    std::vector<int> centre(w * h, 0);
    int seen = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const SurfaceInteraction si = scene.intersect(camera.generate_ray(Vec2f(x + 0.5f, y + 0.5f)));
            centre[y * w + x] = si.valid() && scene.shapes[si.shape].emitter >= 0;
            seen += centre[y * w + x];
        }
    ASSERT_GT(seen, 0) << "the light is not in view";
    const std::vector<float> coverage = pipeline::emitter_coverage(scene, w, h);
    const std::vector<float> own = pipeline::emitter_mask(coverage, {}, w, h, 0);
    const std::vector<float> dilated = pipeline::emitter_mask(coverage, {}, w, h);
    int in_mask = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int p = y * w + x;
            if (centre[p]) {
                EXPECT_EQ(own[p], 1.f) << x << "," << y;
            }
            in_mask += own[p] != 0.f;
            if (own[p] == 0.f) continue;
            bool next_to_centre = false;
            for (int v = std::max(0, y - 1); v <= std::min(h - 1, y + 1); ++v)
                for (int u = std::max(0, x - 1); u <= std::min(w - 1, x + 1); ++u) next_to_centre |= centre[v * w + u];
            EXPECT_TRUE(next_to_centre) << x << "," << y;
        }
    EXPECT_LT(in_mask, w * h / 4) << "the mask covers more than the light";
    EXPECT_EQ(dilated, pipeline::dilate_mask(own, w, h, pipeline::kEmitterMaskDilation));
}

// Against the training view: nothing where the light is where it was; after the light moved,
// the pixels it left and those it entered, and only pixels it is seen in before or after.
TEST(EmitterRefiner, MaskMarksWhereTheLightIsSeenOtherwiseThanInTraining) {
    Scene scene = load_scene(kBox);
    const int w = 24, h = 24;
    const std::vector<float> training = pipeline::emitter_coverage(scene, w, h);
    const std::vector<float> none = pipeline::emitter_mask(training, training, w, h);
    EXPECT_TRUE(std::all_of(none.begin(), none.end(), [](float m) { return m == 0.f; }));
    int light = -1;
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (scene.shapes[i].emitter >= 0) light = int(i);
    ASSERT_GE(light, 0);
    for (Vec3f& v : scene.shapes[light].mesh.positions) v.x() += 1.f;  // the box is 5.56 wide
    scene.build();
    const std::vector<float> now = pipeline::emitter_coverage(scene, w, h);
    const std::vector<float> was_seen = pipeline::emitter_mask(training, {}, w, h, 0);
    const std::vector<float> is_seen = pipeline::emitter_mask(now, {}, w, h, 0);
    const std::vector<float> moved = pipeline::emitter_mask(now, training, w, h, 0);
    int left = 0, entered = 0;
    for (int p = 0; p < w * h; ++p) {
        if (moved[p] != 0.f) {
            EXPECT_TRUE(was_seen[p] != 0.f || is_seen[p] != 0.f) << p;
        }
        left += was_seen[p] != 0.f && is_seen[p] == 0.f;
        entered += was_seen[p] == 0.f && is_seen[p] != 0.f;
        if (was_seen[p] != is_seen[p]) {
            EXPECT_EQ(moved[p], 1.f) << p;
        }
    }
    EXPECT_GT(left, 0) << "the move is too small for the test";
    EXPECT_GT(entered, 0) << "the move is too small for the test";
    EXPECT_EQ(pipeline::emitter_mask(now, training, w, h), pipeline::dilate_mask(moved, w, h, 2));
}

TEST(EmitterRefiner, TakesTheEmitterRefinersValuesExactlyWhereTheMaskIsSet) {
    const std::vector<float> refined = {1, 2, 3, 4, 5, 6}, emitters = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f};
    const std::vector<float> out = pipeline::take_near_emitters(refined, emitters, {0, 1, 0}, 2);
    EXPECT_EQ(out, (std::vector<float>{1, 2, 0.3f, 0.4f, 5, 6}));
}

// Without refiner.pt there is nothing to blend into: an error naming it, before any training.
// Refiners that read different inputs cannot share a view: an error naming the emitter refiner.
TEST(EmitterRefiner, NeedsTheMainRefinerAndItsInputs) {
    const std::string fitdir = small_fit(test::temp_dir("emitter-refiner-errors"), false);
    test::expect_error_naming([&] { pipeline::run_refine(emitter_job(fitdir)); }, {"refiner.pt", "not found"},
                              "an emitter refiner was trained without a main refiner");
    EXPECT_FALSE(fs::exists(fs::path(fitdir) / pipeline::kEmitterRefinerFile));
    RefinerConfig main, emitters;
    main.terms = true;
    test::expect_error_naming([&] { pipeline::check_emitter_refiner_inputs(main, emitters, "x/refiner_emitters.pt"); },
                              {"x/refiner_emitters.pt", "--inputs"}, "refiners with other inputs were paired");
}

// Its record joins the main refiner's cells in metrics.json: one that is not JSON would lose
// them, so it is an error naming the file, before any training.
TEST(EmitterRefiner, RefusesAMalformedMetricsFile) {
    const std::string fitdir = small_fit(test::temp_dir("emitter-refiner-metrics"));
    write_text_atomic(fitdir + "/metrics.json", "{\"refined\": ");
    test::expect_error_naming([&] { pipeline::run_refine(emitter_job(fitdir)); }, {"metrics.json", "JSON object"},
                              "an emitter refiner overwrote a malformed metrics.json");
    EXPECT_FALSE(fs::exists(fs::path(fitdir) / pipeline::kEmitterRefinerFile));
    EXPECT_EQ(read_file(fitdir + "/metrics.json"), "{\"refined\": ");
}

// The training view keeps the main refiner's output (latent_refined.exr and metrics.json's
// cells unchanged, the record added); an edited frame that moves the light is the main
// refiner's output with the emitter refiner's on the mask, computed here from the two files.
TEST(EmitterRefiner, EditedFramesTakeItsOutputWhereTheLightMoved) {
    const std::string fitdir = small_fit(test::temp_dir("emitter-refiner-blend"));
    const std::string refined_before = read_file(fitdir + "/latent_refined.exr");
    const nlohmann::json metrics_before = nlohmann::json::parse(read_file(fitdir + "/metrics.json"));
    const pipeline::RefineSummary s = pipeline::run_refine(emitter_job(fitdir));
    EXPECT_EQ(read_file(fitdir + "/latent_refined.exr"), refined_before);
    const nlohmann::json metrics = nlohmann::json::parse(read_file(fitdir + "/metrics.json"));
    EXPECT_EQ(metrics["refined"], metrics_before["refined"]);
    EXPECT_EQ(metrics["refiner"], metrics_before["refiner"]);
    EXPECT_EQ(metrics["emitter_refiner"]["iterations"], 3);
    EXPECT_EQ(s.metrics, metrics);
    const auto main = Refiner::load(fitdir + "/refiner.pt");
    const auto emitters = Refiner::load(fitdir + "/" + pipeline::kEmitterRefinerFile);

    pipeline::EditSession session(fitdir, std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/edits-demo.json");
    const pipeline::FrameLatents f0 = session.frame(0, 2, 5);
    EXPECT_EQ(f0.refined, main->refine(f0.view)) << "the unedited view is not the main refiner's";
    const std::vector<float> training = pipeline::emitter_coverage(*session.fit().scene, f0.width, f0.height);
    const pipeline::FrameLatents f = session.frame(3, 2, 5);  // the light and the camera moved
    const std::vector<float> mask = pipeline::emitter_mask(
        pipeline::emitter_coverage(*session.fit().scene, f.width, f.height), training, f.width, f.height);
    const std::vector<float> a = main->refine(f.view), b = emitters->refine(f.view);
    ASSERT_EQ(f.refined.size(), a.size());
    int inside = 0, outside = 0, differ = 0;
    for (size_t i = 0; i < f.refined.size(); ++i) {
        const bool near = mask[i / 16] != 0.f;
        EXPECT_EQ(f.refined[i], near ? b[i] : a[i]) << i;
        (near ? inside : outside) += i % 16 == 0;
        differ += near && a[i] != b[i];
    }
    EXPECT_GT(inside, 0);
    EXPECT_GT(outside, 0);
    EXPECT_GT(differ, 0) << "the two refiners agree: the test cannot tell them apart";

    // A new stage 1 in the folder makes the emitter refiner stale: its files go, and so does its
    // record when the main refiner writes metrics.json again.
    small_fit(fs::path(fitdir).parent_path().string());
    for (const char* name : {pipeline::kEmitterRefinerFile, pipeline::kEmitterRefinerCheckpoint,
                             pipeline::kEmitterRefinerLoss, "refiner_emitters_checkpoint.json"})
        EXPECT_FALSE(fs::exists(fs::path(fitdir) / name)) << name;
    EXPECT_FALSE(nlohmann::json::parse(read_file(fitdir + "/metrics.json")).contains("emitter_refiner"));
}
