// Refiner (stage 2): identity at start, training lowers the loss on a problem it can solve,
// save/load and checkpoint/resume reproduce outputs exactly, LPIPS through the TAESD3 decoder
// gives finite gradients, noise views and examples are drawn evenly, cosine decay scales the steps, windowed
// inference averages the windows it says, and bad files are clear errors. The U-Net body:
// test_refiner_unet.cpp.
#include "autodiff/fit.h"
#include "core/scene_loader.h"
#include "integrators/aov.h"
#include "refiner/refiner.h"
#include "refiner/refiner_problem.h"
#include "test_util.h"
#include "vae/lpips.h"
#include "vae/vae.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <limits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

using namespace lpt;
using namespace lpt::refiner_test;

namespace {

/// Training that never moves the weights (lr 0, latent MSE alone): the network stays the
/// identity, so a step's loss shows which view or example it drew.
RefinerTrainOptions still_training(int iterations, int crop) {
    RefinerTrainOptions o = latent_training(iterations, crop);
    o.lr = 0.f;
    o.w_ssim = 0.f;
    return o;
}

/// Example k of the result is sources[k]'s view with target = its latent − k: under
/// still_training it scores latent MSE k².
std::vector<RefinerExample> offset_examples(const std::vector<const Problem*>& sources) {
    std::vector<RefinerExample> examples;
    for (size_t k = 0; k < sources.size(); ++k) {
        RefinerExample e{sources[k]->in, sources[k]->in.latent, {}};
        for (float& v : e.target) v -= float(k);
        examples.push_back(e);
    }
    return examples;
}

/// The window [x0, x0 + w) × [y0, y0 + h) of a view.
RefinerInput crop_of(const RefinerInput& in, int x0, int y0, int w, int h) {
    RefinerInput c;
    c.width = w;
    c.height = h;
    for (int y = y0; y < y0 + h; ++y)
        for (int x = x0; x < x0 + w; ++x) {
            const size_t i = size_t(y) * size_t(in.width) + size_t(x);
            c.latent.insert(c.latent.end(), in.latent.begin() + long(i * kC), in.latent.begin() + long((i + 1) * kC));
            c.normal.insert(c.normal.end(), in.normal.begin() + long(i * 3), in.normal.begin() + long((i + 1) * 3));
            c.distance.push_back(in.distance[i]);
        }
    return c;
}

/// Largest difference between a refined crop and the same pixels of the refined whole view,
/// over the crop's interior: pixels further than the receptive-field radius (1 + 2 + 1 for the
/// 3×3, 5×5, 3×3 blocks) from its edges, which see no padding.
double crop_vs_whole(const Refiner& r, const RefinerInput& in, int x0, int y0, int w, int h) {
    const std::vector<float> whole = r.refine(in), part = r.refine(crop_of(in, x0, y0, w, h));
    constexpr int kRadius = 4;
    double worst = 0;
    for (int y = kRadius; y < h - kRadius; ++y)
        for (int x = kRadius; x < w - kRadius; ++x)
            for (int c = 0; c < kC; ++c) {
                const size_t a = (size_t(y) * size_t(w) + size_t(x)) * kC + size_t(c);
                const size_t b = (size_t(y + y0) * size_t(in.width) + size_t(x + x0)) * kC + size_t(c);
                worst = std::max(worst, double(std::abs(part[a] - whole[b])));
            }
    return worst;
}

/// With lr 0 the network stays the identity, so an iteration that drew view k, whose latent is
/// its target + k, records latent MSE k². Each of the n views must be drawn about equally often.
void expect_offsets_drawn_evenly(const RefinerTrainResult& res, int n) {
    std::vector<int> drawn(size_t(n), 0);
    for (const RefinerRecord& rec : res.history) {
        const int k = int(std::lround(std::sqrt(rec.mse)));
        ASSERT_LT(k, n) << "iteration " << rec.iteration;
        ASSERT_NEAR(rec.mse, double(k * k), 1e-6) << "iteration " << rec.iteration;
        ++drawn[size_t(k)];
    }
    const double expected = double(res.history.size()) / n, sd = std::sqrt(expected * (1.0 - 1.0 / n));
    for (int k = 0; k < n; ++k) EXPECT_NEAR(drawn[size_t(k)], expected, 4.5 * sd) << "view " << k;
}

}  // namespace

TEST(Refiner, StartsAsIdentityAndRejectsBadViews) {
    Problem p = make_problem(12, 9);
    auto r = Refiner::create(RefinerConfig{}, 3);
    EXPECT_EQ(r->refine(p.in), p.in.latent);
    EXPECT_GT(r->parameter_count(), 16 * 16 * 25 * 256);  // the 5x5 block alone
    RefinerInput bad = p.in;
    bad.normal.pop_back();
    EXPECT_THROW(r->refine(bad), std::invalid_argument);
    EXPECT_THROW(Refiner::create(RefinerConfig{16, 0}, 0), std::invalid_argument);
}

TEST(Refiner, TrainingLowersTheLossAndKeepsTheBest) {
    Problem p = make_problem(16, 16);
    auto r = Refiner::create(small(), 1);
    const double before = mse(r->refine(p.in), p.target);
    const RefinerTrainOptions o = latent_training(150, 12);
    RefinerTrainResult res = r->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    ASSERT_EQ(res.history.size(), 150u);
    const double after = mse(r->refine(p.in), p.target);
    // The perturbation is a smooth function of the inputs: most of it must be learned.
    EXPECT_LT(after, 0.25 * before) << "before " << before << " after " << after;
    EXPECT_LT(res.history.back().smoothed, res.history.front().loss);
    EXPECT_GT(res.history.front().dssim, 0.0);
}

// Noise views: one view, or several identical ones, train bit-identically to the single-view
// call (the view draw must not move the crops or the dropout); views that differ are all drawn,
// about equally often. The drawn view shows in iteration records: with lr 0 the network stays the
// identity (its head starts at zero), so a view offset by k from the target has latent MSE k².
TEST(Refiner, NoiseViewsAreDrawnEvenlyAndOneViewTrainsAsBefore) {
    Problem p = make_problem(16, 16);
    RefinerConfig cfg = small();
    cfg.dropout = 0.1f;  // dropout masks are drawn per iteration too
    const RefinerTrainOptions o = latent_training(20, 12);
    auto single = Refiner::create(cfg, 3), twice = Refiner::create(cfg, 3);
    single->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    twice->train(std::vector<RefinerInput>{p.in, p.in}, p.target, nullptr, nullptr, nullptr, o);
    EXPECT_EQ(single->refine(p.in), twice->refine(p.in));

    std::vector<RefinerInput> views(3, p.in);
    for (int k = 0; k < 3; ++k)
        for (size_t i = 0; i < p.in.latent.size(); ++i) views[size_t(k)].latent[i] = p.target[i] + float(k);
    const RefinerTrainOptions still = still_training(150, 8);
    auto r = Refiner::create(cfg, 5);
    const RefinerTrainResult res = r->train(views, p.target, nullptr, nullptr, nullptr, still);
    expect_offsets_drawn_evenly(res, 3);

    views[1].width = 8;
    EXPECT_THROW(r->train(views, p.target, nullptr, nullptr, nullptr, still), std::invalid_argument);
}

// Examples (augmented views) bring their own target and may differ in size: with lr 0 the
// network stays the identity, so example k, whose target is its latent − k, shows as latent MSE k²
// in the iterations that drew it; all are drawn about equally often, the 16 × 12 one (a turned
// 12 × 16 view) with crops that fit it; one example trains exactly as the single-view call; a
// target of the wrong size is an error.
TEST(Refiner, ExamplesBringTheirOwnTargetsAndSizes) {
    Problem p = make_problem(12, 16), q = make_problem(16, 12);
    RefinerConfig cfg = small();
    cfg.dropout = 0.1f;
    auto single = Refiner::create(cfg, 3), one = Refiner::create(cfg, 3);
    const RefinerTrainOptions o = latent_training(20, 10);
    single->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    one->train(std::vector<RefinerExample>{{p.in, p.target, {}}}, nullptr, nullptr, o);
    EXPECT_EQ(single->refine(p.in), one->refine(p.in));

    std::vector<RefinerExample> examples = offset_examples({&p, &q, &p});
    const RefinerTrainOptions still = still_training(150, 14);
    auto r = Refiner::create(cfg, 5);
    const RefinerTrainResult res = r->train(examples, nullptr, nullptr, still);
    expect_offsets_drawn_evenly(res, 3);

    examples[2].target.pop_back();
    EXPECT_THROW(r->train(examples, nullptr, nullptr, still), std::invalid_argument);
    EXPECT_THROW(r->train(std::vector<RefinerExample>{}, nullptr, nullptr, still), std::invalid_argument);
}

// Cosine decay: step i uses lr · (1 + cos(π i / N)) / 2. Two runs of N = 2 steps from one start,
// constant and decayed, take the same first step (lr) and then the same Adam direction from the
// same weights, the decayed one at half the rate (cos(π/2) = 0), so its second step moves the
// refined view half as far (to first order in the small lr).
TEST(Refiner, CosineDecayScalesEachStepByTheSchedule) {
    Problem p = make_problem(12, 12);
    RefinerTrainOptions o = latent_training(1, 0);  // whole view: both steps see the same data
    o.lr = 3e-5f;
    o.w_ssim = 0.f;
    o.min_delta = 0.f;  // a small step's smoothed gain (2 % of it) still counts as the best weights
    auto one = Refiner::create(small(), 4);
    one->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    const std::vector<float> start = one->refine(p.in);
    o.iterations = 2;
    auto steps = [&](bool cosine) {
        RefinerTrainOptions oc = o;
        oc.cosine_decay = cosine;
        auto r = Refiner::create(small(), 4);
        const RefinerTrainResult res = r->train(p.in, p.target, nullptr, nullptr, nullptr, oc);
        // The second step lowered the loss, so the kept (best smoothed) weights are the last ones.
        EXPECT_LT(res.history[1].loss, res.history[0].loss);
        std::vector<float> moved = r->refine(p.in);
        for (size_t i = 0; i < moved.size(); ++i) moved[i] -= start[i];
        return moved;
    };
    const std::vector<float> constant = steps(false), decayed = steps(true);
    double dot = 0, norm = 0;
    for (size_t i = 0; i < constant.size(); ++i) {
        dot += double(decayed[i]) * constant[i];
        norm += double(constant[i]) * constant[i];
    }
    ASSERT_GT(norm, 0.0);
    std::cout << "second step, decayed against constant: " << dot / norm << " (schedule: 0.5)\n";
    EXPECT_NEAR(dot / norm, 0.5, 0.02);
}

// A non-finite loss (injected: a NaN in the target) refuses the step instead of aborting the run;
// the weights stay as they were, and the steps after it still train.
TEST(Refiner, NonFiniteStepsAreRefusedAndTheWeightsKept) {
    Problem p = make_problem(12, 12);
    auto r = Refiner::create(small(), 2);
    const std::vector<float> identity = r->refine(p.in);
    RefinerTrainOptions o;
    o.iterations = 4;
    o.crop = 0;
    o.w_lpips = 0.f;
    o.patience = 0;
    std::vector<float> poisoned = p.target;
    poisoned[5] = std::numeric_limits<float>::quiet_NaN();
    const RefinerTrainResult bad = r->train(p.in, poisoned, nullptr, nullptr, nullptr, o);
    ASSERT_EQ(bad.history.size(), 4u);
    for (const RefinerRecord& rec : bad.history) {
        EXPECT_TRUE(rec.refused);
        EXPECT_EQ(rec.refused_parameter, "loss");
        EXPECT_TRUE(std::isfinite(rec.smoothed));
    }
    EXPECT_EQ(r->refine(p.in), identity) << "a refused step changed the weights";
    const RefinerTrainResult good = r->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    EXPECT_FALSE(good.history.back().refused);
    EXPECT_NE(r->refine(p.in), identity);
}

TEST(Refiner, SaveLoadAndResumeReproduceOutputs) {
    Problem p = make_problem(14, 12);
    RefinerConfig cfg = small();
    cfg.dropout = 0.1f;  // masks must replay too
    cfg.distance_scale = 2.5f;
    RefinerTrainOptions o;
    o.iterations = 12;
    o.crop = 11;
    o.w_lpips = 0.f;
    o.patience = 0;
    o.seed = 9;
    auto full = Refiner::create(cfg, 5);
    full->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    const std::vector<float> expect = full->refine(p.in);

    const std::string ck = temp_path("ck.pt");
    std::filesystem::remove(ck);
    auto part = Refiner::create(cfg, 5);
    o.checkpoint_path = ck;
    o.checkpoint_every = 0;
    o.iterations = 5;  // "killed" after 5 iterations; its checkpoint is written at the end
    part->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    auto resumed = Refiner::create(cfg, 123);  // different init: everything must come from the file
    o.iterations = 12;
    o.resume = true;
    RefinerTrainResult res = resumed->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    EXPECT_EQ(res.history.size(), 12u);
    EXPECT_EQ(resumed->refine(p.in), expect);

    const std::string file = temp_path("refiner.pt");
    full->save(file);
    auto loaded = Refiner::load(file);
    EXPECT_EQ(loaded->refine(p.in), expect);
    EXPECT_EQ(loaded->config().distance_scale, 2.5f);
    EXPECT_EQ(loaded->config().expansion, 2);

    // temp_path writes an empty file: name the paths once (an empty file, junk, a missing one).
    test::expect_error_naming([] { Refiner::load(temp_path("empty.pt")); }, {"empty.pt"}, "an empty file accepted");
    const std::string junk = temp_path("junk.pt");
    std::ofstream(junk) << "not a refiner";
    test::expect_error_naming([&] { Refiner::load(junk); }, {"junk.pt"}, "junk accepted");
    const std::string missing = test::temp_dir("refiner-missing") + "/missing.pt";
    test::expect_error_naming([&] { Refiner::load(missing); }, {"missing.pt"}, "a missing file accepted");
}

// Without InstanceNorm the refiner is a plain convolution network: a crop's interior is refined
// exactly as the whole view refines those pixels (its 4-pixel border sees zero padding instead
// of neighbours). With InstanceNorm (the default) the crop's own statistics change every pixel.
// The choice survives save/load.
TEST(Refiner, WithoutInstanceNormACropIsRefinedAsTheWholeView) {
    Problem p = make_problem(24, 20);
    RefinerTrainOptions o = latent_training(20, 12);
    RefinerConfig cfg = small();
    cfg.instance_norm = false;
    auto plain = Refiner::create(cfg, 4);
    plain->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    auto normed = Refiner::create(small(), 4);
    normed->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    ASSERT_GT(mse(plain->refine(p.in), p.in.latent), 1e-4) << "training left the refiner the identity";

    EXPECT_LT(crop_vs_whole(*plain, p.in, 5, 3, 14, 12), 1e-5);
    EXPECT_GT(crop_vs_whole(*normed, p.in, 5, 3, 14, 12), 1e-3);
    EXPECT_LT(plain->parameter_count(), normed->parameter_count());  // no affine norm weights

    const std::string file = temp_path("plain_refiner.pt");
    plain->save(file);
    auto loaded = Refiner::load(file);
    EXPECT_FALSE(loaded->config().instance_norm);
    EXPECT_EQ(loaded->refine(p.in), plain->refine(p.in));

    // A checkpoint of the other network cannot be resumed: the error names the option.
    const std::string ck = temp_path("normed_ck.pt");
    std::filesystem::remove(ck);
    o.iterations = 2;
    o.checkpoint_path = ck;
    Refiner::create(small(), 4)->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    o.iterations = 4;
    o.resume = true;
    test::expect_error_naming([&] { Refiner::create(cfg, 4)->train(p.in, p.target, nullptr, nullptr, nullptr, o); },
                              {"--norm instance"}, "an InstanceNorm checkpoint resumed without InstanceNorm");
}

/// The largest difference between `out` and the per-pixel mean of `windowed` applied to the
/// side × side windows of `in` at the origins xs × ys, each window also checked against `whole`
/// (the same training without windows).
double distance_to_window_mean(const std::vector<float>& out, const Refiner& windowed, const Refiner& whole,
                               const RefinerInput& in, int side, const std::vector<int>& xs,
                               const std::vector<int>& ys) {
    std::vector<double> sum(out.size(), 0.0), count(out.size(), 0.0);
    for (int y0 : ys)
        for (int x0 : xs) {
            const RefinerInput window = crop_of(in, x0, y0, side, side);
            const std::vector<float> part = windowed.refine(window);
            EXPECT_EQ(part, whole.refine(window)) << "the window changed training, not just inference";
            for (int y = 0; y < side; ++y)
                for (int x = 0; x < side; ++x)
                    for (int c = 0; c < kC; ++c) {
                        const size_t i = (size_t(y0 + y) * size_t(in.width) + size_t(x0 + x)) * kC + size_t(c);
                        sum[i] += part[(size_t(y) * size_t(side) + size_t(x)) * kC + size_t(c)];
                        count[i] += 1.0;
                    }
        }
    double worst = 0;
    for (size_t i = 0; i < out.size(); ++i) {
        EXPECT_GT(count[i], 0.0) << "pixel " << i / kC << " is in no window";
        worst = std::max(worst, std::abs(out[i] - sum[i] / count[i]));
    }
    return worst;
}

// Windowed inference (RefinerConfig::tile, docs/refiner.md "Windows"): the refined view is, per
// pixel, the mean of the refiner applied to every tile×tile window at stride tile/2, the last
// window flush with the far edge; checked against those windows refined one by one, at origins
// written out by hand. The window changes inference only: the same training with tile 0 refines
// each window identically, and its whole-view output differs (InstanceNorm statistics).
TEST(Refiner, WindowsAverageTheRefinedWindowsOfTheTrainingCropSize) {
    Problem p = make_problem(21, 13);
    RefinerConfig cfg = small();
    cfg.tile = 8;
    auto windowed = Refiner::create(cfg, 5), whole = Refiner::create(small(), 5);
    windowed->train(p.in, p.target, nullptr, nullptr, nullptr, latent_training(30, 8));
    whole->train(p.in, p.target, nullptr, nullptr, nullptr, latent_training(30, 8));
    const std::vector<float> out = windowed->refine(p.in);
    // 21 and 13 pixels, windows of 8 every 4
    EXPECT_LT(distance_to_window_mean(out, *windowed, *whole, p.in, 8, {0, 4, 8, 12, 13}, {0, 4, 5}), 1e-5);
    EXPECT_GT(mse(out, whole->refine(p.in)), 1e-8) << "windows gave the whole view's output";

    const std::string file = temp_path("windowed_refiner.pt");
    windowed->save(file);
    auto loaded = Refiner::load(file);
    EXPECT_EQ(loaded->config().tile, 8);
    EXPECT_EQ(loaded->config().window_stride, 0) << "a file with the old rule must load with it";
    EXPECT_EQ(loaded->refine(p.in), out);
}

// RefinerConfig::window_stride: the same mean over windows at the stride it names (the last
// window still flush with the far edge), a stride longer than a window shortened to it so that
// no pixel is left out, and the stride kept in refiner.pt.
TEST(Refiner, WindowStrideSetsTheWindowOrigins) {
    Problem p = make_problem(21, 13);
    RefinerConfig cfg = small();
    cfg.tile = 8;
    cfg.window_stride = 3;
    auto windowed = Refiner::create(cfg, 5), whole = Refiner::create(small(), 5);
    windowed->train(p.in, p.target, nullptr, nullptr, nullptr, latent_training(30, 8));
    whole->train(p.in, p.target, nullptr, nullptr, nullptr, latent_training(30, 8));
    const std::vector<float> out = windowed->refine(p.in);
    EXPECT_LT(distance_to_window_mean(out, *windowed, *whole, p.in, 8, {0, 3, 6, 9, 12, 13}, {0, 3, 5}), 1e-5);
    cfg.window_stride = 0;
    auto halves = Refiner::create(cfg, 5);
    halves->train(p.in, p.target, nullptr, nullptr, nullptr, latent_training(30, 8));
    EXPECT_GT(mse(out, halves->refine(p.in)), 1e-10) << "stride 3 gave the stride-4 windows' output";

    const std::string file = temp_path("strided_refiner.pt");
    windowed->save(file);
    auto loaded = Refiner::load(file);
    EXPECT_EQ(loaded->config().window_stride, 3);
    EXPECT_EQ(loaded->refine(p.in), out);

    cfg.window_stride = 20;  // longer than the window: every 8 pixels, the last flush
    auto sparse = Refiner::create(cfg, 5);
    sparse->train(p.in, p.target, nullptr, nullptr, nullptr, latent_training(30, 8));
    EXPECT_LT(distance_to_window_mean(sparse->refine(p.in), *sparse, *whole, p.in, 8, {0, 8, 13}, {0, 5}), 1e-5);
}

TEST(Refiner, LpipsThroughTheDecoderTrains) {
    const std::string shared = test::shared_dir();
    if (shared.empty() || !std::filesystem::exists(shared + "/models/lpips/lpips_squeeze_v0.1.safetensors"))
        GTEST_SKIP() << "TAESD3/LPIPS weights not found (set LATENTPT_SHARED)";
    auto vae = load_taesd(shared + "/models/taesd3");
    auto lpips = Lpips::load(shared + "/models/lpips");
    Problem p = make_problem(12, 12);
    auto r = Refiner::create(small(), 2);
    const std::vector<float> rgb = vae->decode(p.target, 12, 12);
    RefinerTrainOptions o;
    o.iterations = 8;
    o.lr = 2e-3f;
    o.crop = 0;
    o.lpips_crop = 4;  // 32x32 RGB
    o.w_mse = 0.f;
    o.w_ssim = 0.f;
    o.w_lpips = 1.f;
    o.patience = 0;
    RefinerTrainResult res = r->train(p.in, p.target, &rgb, vae.get(), lpips.get(), o);
    ASSERT_EQ(res.history.size(), 8u);
    for (const RefinerRecord& rec : res.history) EXPECT_TRUE(std::isfinite(rec.lpips) && rec.lpips > 0.0);
    // LPIPS alone moved the weights: the refiner is no longer the identity.
    EXPECT_NE(r->refine(p.in), p.in.latent);
}

// The refiner on a tiny rendered scene: the Cornell box's latent rendered from one set of
// parameters is refined toward the render of another set, with the AOVs of the same view.
// The residual is scene structure (per-shape colour differences), which normals and distance
// identify, so the full-view error must drop.
TEST(Refiner, LossDecreasesOnATinyRenderedScene) {
    const int res = 16;
    Scene scene = load_scene(
        std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json",
        {{"camera.width", std::to_string(res)}, {"camera.height", std::to_string(res)}, {"integrator.max_depth", "3"}});
    LatentModel fitted(scene, Parameterisation::Code, 1), truth(scene, Parameterisation::Code, 2);
    const RenderOptions ro = RenderOptions::from_scene(scene, res, res, 16, 3);
    const std::vector<float> latent = render_toned(fitted, ro, ToneCurve::Clip),
                             target = render_toned(truth, ro, ToneCurve::Clip);
    AovImages aov = render_aovs(scene, SceneSpectra<3>::from_description(scene), res, res, ro.spp, ro.seed);
    RefinerInput in{res, res, latent, aov.normal, aov.distance, {}, {}};  // no terms, no emitter cells
    RefinerConfig cfg = small();
    cfg.distance_scale = 5.f;
    auto r = Refiner::create(cfg, 4);
    RefinerTrainOptions o;
    o.iterations = 120;
    o.lr = 3e-3f;
    o.crop = 0;
    o.w_lpips = 0.f;
    o.patience = 0;
    RefinerTrainResult res_ = r->train(in, target, nullptr, nullptr, nullptr, o);
    const double before = mse(latent, target), after = mse(r->refine(in), target);
    EXPECT_LT(after, 0.5 * before) << "before " << before << " after " << after;
    EXPECT_LT(res_.history.back().smoothed, res_.history.front().loss);
}
