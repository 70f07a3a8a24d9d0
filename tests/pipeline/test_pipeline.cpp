// The pipeline library called without the CLI: a fit that is cancelled mid-way leaves no result
// files, and resuming it ends bit-identical to an uninterrupted run; an edit sequence renders;
// the refiner's noise views are rendered from the fit folder.
#include "core/image_io.h"
#include "pipeline/edit.h"
#include "pipeline/edit_session.h"
#include "pipeline/fit.h"
#include "pipeline/fit_checkpoint.h"
#include "pipeline/refine.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <filesystem>
#include <fstream>
#include <functional>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <map>

using namespace lpt;
namespace fs = std::filesystem;

namespace {

pipeline::FitJob small_fit(const std::string& out) {
    pipeline::FitJob job;
    job.scene = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json";
    job.defines = {{"integrator.max_depth", "3"}};
    job.out = out;
    job.synthetic_res = "8x8";
    job.options.iterations = 30;
    job.options.spp = 2;
    job.options.checkpoint_every = 8;
    job.final_spp = 4;
    job.refiner = false;
    return job;
}

/// A small fit in <dir>/fit and a stage-2 job on it (the narrowest network).
pipeline::RefineJob small_refine(const std::string& dir, int iterations) {
    pipeline::run_fit(small_fit(dir + "/fit"));
    pipeline::RefineJob r;
    r.fitdir = dir + "/fit";
    r.net.expansion = 1;
    r.train.iterations = iterations;
    return r;
}

/// A small fit in <dir>/fit and the demo edit sequence on it into <dir>/edit, at 2 spp.
pipeline::EditJob demo_edit_of_a_small_fit(const std::string& dir) {
    pipeline::run_fit(small_fit(dir + "/fit"));
    pipeline::EditJob edit;
    edit.fitdir = dir + "/fit";
    edit.edits = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/edits-demo.json";
    edit.out = dir + "/edit";
    edit.spp = 2;
    return edit;
}

pipeline::Reporter cancel_after(int step) {
    pipeline::Reporter r;
    r.progress = [step](const pipeline::StageProgress& p) { return p.step < step; };
    return r;
}

}  // namespace

TEST(Pipeline, CancelledFitWritesNoResultAndResumesToTheUninterruptedParameters) {
    const std::string dir = test::temp_dir("pipeline-fit");
    const pipeline::FitSummary whole = pipeline::run_fit(small_fit(dir + "/whole"));
    EXPECT_EQ(whole.state.next_iteration, 30);

    pipeline::FitJob job = small_fit(dir + "/cancelled");
    EXPECT_THROW(pipeline::run_fit(job, cancel_after(20)), pipeline::Cancelled);
    EXPECT_FALSE(fs::exists(job.out + "/params.json")) << "a cancelled fit must not look finished";
    EXPECT_TRUE(fs::exists(job.out + "/checkpoint/state.json"));

    job.resume = true;
    const pipeline::FitSummary resumed = pipeline::run_fit(job);
    EXPECT_EQ(read_file(job.out + "/params.json"), read_file(dir + "/whole/params.json"));
    EXPECT_EQ(resumed.final_loss, whole.final_loss);
}

TEST(Pipeline, ResumeRefusesOrRestartsACheckpointOfOtherSettings) {
    // A finished fit, rerun with another emission decay: --resume must not continue (finish at
    // once with) the old parameters. Strict: an error naming settings.json and the setting;
    // with restart_if_changed: the fit runs from the start and equals a fresh one.
    const std::string dir = test::temp_dir("pipeline-fit-changed");
    pipeline::FitJob job = small_fit(dir + "/fit");
    pipeline::run_fit(job);
    job.options.emission_decay = 0.5f;
    job.resume = true;
    test::expect_error_naming([&] { pipeline::run_fit(job); }, {"checkpoint/settings.json", "emission_decay"},
                              "resumed a checkpoint made with another emission decay");
    job.restart_if_changed = true;
    const pipeline::FitSummary restarted = pipeline::run_fit(job);
    pipeline::FitJob fresh = small_fit(dir + "/fresh");
    fresh.options.emission_decay = 0.5f;
    pipeline::run_fit(fresh);
    EXPECT_EQ(read_file(job.out + "/params.json"), read_file(fresh.out + "/params.json"))
        << "the old fit was continued";
    // The same settings again resume (nothing left to do) rather than restart.
    const pipeline::FitSummary again = pipeline::run_fit(job);
    EXPECT_EQ(again.state.history.size(), restarted.state.history.size());
    EXPECT_EQ(read_file(job.out + "/params.json"), read_file(fresh.out + "/params.json"));
    // --resume with no checkpoint at all is an error too.
    pipeline::FitJob none = small_fit(dir + "/none");
    none.resume = true;
    EXPECT_THROW(pipeline::run_fit(none), std::runtime_error);
}

// The scene's text, not only its path: a max_depth edited in the file was resumed, the same
// change given as -D refused. A checkpoint that records no text resumes as before.
TEST(Pipeline, ResumeRefusesACheckpointOfAnEditedSceneFile) {
    const std::string dir = test::temp_dir("pipeline-fit-scene-edited");
    const std::string scene = dir + "/scene.json";
    fs::copy_file(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json", scene);
    pipeline::FitJob job = small_fit(dir + "/fit");
    job.scene = scene;
    job.defines.clear();
    pipeline::run_fit(job);
    std::string text = read_file(scene);
    const size_t at = text.find("\"max_depth\": 8");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, 14, "\"max_depth\": 3");
    std::ofstream(scene) << text;
    job.resume = true;
    test::expect_error_naming([&] { pipeline::run_fit(job); }, {"checkpoint/settings.json", "scene_text"},
                              "resumed a checkpoint of the scene file before its edit");
    nlohmann::json recorded = nlohmann::json::parse(read_file(job.out + "/checkpoint/settings.json"));
    recorded.erase("scene_text");  // as checkpoints before session 55 were
    std::ofstream(job.out + "/checkpoint/settings.json") << recorded.dump();
    EXPECT_NO_THROW(pipeline::run_fit(job));
}

// A finished fit rerun with another stage-1 setting starts stage 1 again; killed there and
// resumed, it must train its refiner again rather than resume the old one's finished checkpoint,
// which was trained on the old stage 1's renders: it ends as a fresh fit with the new setting.
TEST(Pipeline, AStage1StartedAgainTrainsItsRefinerAgainWhenResumed) {
    const std::string dir = test::temp_dir("pipeline-stale-refiner");
    auto with_refiner = [](pipeline::FitJob job) {
        job.refiner = true;
        job.refine.net.expansion = 1;
        job.refine.train.iterations = 4;
        return job;
    };
    pipeline::FitJob job = with_refiner(small_fit(dir + "/fit"));
    const pipeline::FitSummary old = pipeline::run_fit(job);
    job.options.emission_decay = 0.5f;
    job.resume = true;
    job.restart_if_changed = true;
    EXPECT_THROW(pipeline::run_fit(job, cancel_after(20)), pipeline::Cancelled);  // in stage 1
    const pipeline::FitSummary resumed = pipeline::run_fit(job);
    pipeline::FitJob fresh = with_refiner(small_fit(dir + "/fresh"));
    fresh.options.emission_decay = 0.5f;
    const pipeline::FitSummary scratch = pipeline::run_fit(fresh);
    ASSERT_TRUE(old.refined && resumed.refined && scratch.refined);
    const std::vector<RefinerRecord>& got = resumed.refined->result.history;
    ASSERT_EQ(got.size(), 4u);
    EXPECT_NE(got.back().loss, old.refined->result.history.back().loss) << "the old refiner was resumed";
    EXPECT_EQ(got.back().loss, scratch.refined->result.history.back().loss);
    EXPECT_EQ(read_file(job.out + "/params.json"), read_file(fresh.out + "/params.json"));
}

// A fit without its refiner into the folder of one with: the old refiner.pt stayed, and edits
// applied it to the new fit's renders.
TEST(Pipeline, AStage1StartedAgainRemovesTheOldRefiner) {
    pipeline::FitJob job = small_fit(test::temp_dir("pipeline-refit") + "/fit");
    job.refiner = true;
    job.refine.net.expansion = 1;
    job.refine.train.iterations = 2;
    pipeline::run_fit(job);
    const char* stage2[] = {"refiner.pt", "refiner_checkpoint.pt", "refiner_loss.csv", "latent_refined.exr",
                            "metrics.json"};
    for (const char* name : stage2) ASSERT_TRUE(fs::exists(job.out + "/" + name)) << name;
    job.refiner = false;
    job.options.seed = 9;
    pipeline::run_fit(job);
    for (const char* name : stage2) EXPECT_FALSE(fs::exists(job.out + "/" + name)) << name << " outlived its fit";
    EXPECT_TRUE(fs::exists(job.out + "/params.json"));
}

// The fit's own checks, not only the CLI's: a caller without it (latentpt.fit in Python) gets an
// error naming the option rather than a fit at zero gradient or a division by a zero period.
TEST(Pipeline, FitOptionsOutOfRangeAreRefusedByName) {
    const pipeline::FitJob good = small_fit(test::temp_dir("pipeline-fit-range") + "/fit");
    const std::vector<std::pair<std::string, std::function<void(pipeline::FitJob&)>>> cases = {
        {"--spp", [](pipeline::FitJob& j) { j.options.spp = -3; }},
        {"--iterations", [](pipeline::FitJob& j) { j.options.iterations = 0; }},
        {"--final-spp", [](pipeline::FitJob& j) { j.final_spp = 0; }},
        {"--lr", [](pipeline::FitJob& j) { j.options.lr = std::nanf(""); }},
        {"--lr-period", [](pipeline::FitJob& j) { j.options.lr_period = 0; }},
        {"--min-delta", [](pipeline::FitJob& j) { j.options.min_delta = -1.f; }},
        {"--reuse-paths", [](pipeline::FitJob& j) { j.options.reuse_paths = -1; }},
        {"--ref-spp", [](pipeline::FitJob& j) { j.ref_spp = -5; }},
    };
    for (const auto& [flag, spoil] : cases) {
        pipeline::FitJob job = good;
        spoil(job);
        test::expect_error_naming<std::invalid_argument>([&] { pipeline::run_fit(job); }, {flag},
                                                         "a fit with a bad " + flag + " was accepted");
    }
    EXPECT_FALSE(fs::exists(good.out + "/params.json"));
}

// Without --resume a fit starts its checkpoint again; one whose inputs are then refused (a
// misspelt resolution, a missing target or VAE) used to have deleted the earlier fit's first.
TEST(Pipeline, AFitWithBadInputsLeavesTheFoldersCheckpoint) {
    const pipeline::FitJob good = small_fit(test::temp_dir("pipeline-fit-keep") + "/fit");
    pipeline::run_fit(good);
    const std::string state = read_file(good.out + "/checkpoint/state.json");
    const std::vector<std::pair<std::string, std::function<void(pipeline::FitJob&)>>> cases = {
        {"--synthetic-res", [](pipeline::FitJob& j) { j.synthetic_res = "8by8"; }},
        {"--encode-res", [](pipeline::FitJob& j) { j.encode = true, j.encode_res = "256"; }},
        {"nope.exr", [](pipeline::FitJob& j) { j.target = "/nonexistent/nope.exr"; }},
        {"/nonexistent/vae", [](pipeline::FitJob& j) { j.encode = true, j.vae.dir = "/nonexistent/vae"; }},
    };
    for (const auto& [named, spoil] : cases) {
        pipeline::FitJob job = good;
        spoil(job);
        test::expect_error_naming<std::exception>([&] { pipeline::run_fit(job); }, {named},
                                                  "a fit with a bad " + named + " was accepted");
        EXPECT_EQ(read_file(good.out + "/checkpoint/state.json"), state) << named;
    }
    pipeline::FitJob again = good;
    again.resume = true;
    std::string said;
    pipeline::Reporter r;
    r.note = [&](const std::string& line) { said += line + "\n"; };
    pipeline::run_fit(again, r);
    EXPECT_NE(said.find("resuming at iteration 30"), std::string::npos) << said;
}

TEST(Pipeline, ACheckpointFromBeforeASettingExistedResumesAtItsOldValueOnly) {
    // settings.json written before --emitter-response-decay existed has no key for it: such a
    // checkpoint was made with μ = 0, so μ = 0 resumes it and any other μ is refused by name.
    // A key missing that is not listed as added later is still an error.
    const pipeline::FitJob job = small_fit(test::temp_dir("pipeline-settings") + "/fit");
    nlohmann::json old = pipeline::stage1_settings(job);
    ASSERT_TRUE(old.contains("emitter_response_decay"));
    old.erase("emitter_response_decay");
    EXPECT_EQ(pipeline::settings_difference(old, pipeline::stage1_settings(job)), "");
    pipeline::FitJob flat = job;
    flat.options.emitter_response_decay = 1e-4f;
    EXPECT_NE(pipeline::settings_difference(old, pipeline::stage1_settings(flat)).find("emitter_response_decay"),
              std::string::npos);
    // the VAE's fingerprint (since session 51): unknown before, so a checkpoint without it resumes
    // whatever the VAE; one that records another VAE does not
    ASSERT_TRUE(old.contains("vae_encoder"));
    nlohmann::json other_vae = old;
    other_vae["vae_encoder"] = "fnv1a64:0000000000000000";
    EXPECT_NE(pipeline::settings_difference(other_vae, pipeline::stage1_settings(job)).find("vae_encoder"),
              std::string::npos);
    old.erase("vae_encoder");
    EXPECT_EQ(pipeline::settings_difference(old, pipeline::stage1_settings(job)), "");
    // the exposure cycle (since session 57): a checkpoint without it resumes only a fit without one
    ASSERT_TRUE(old.contains("exposures"));
    old.erase("exposures");
    EXPECT_EQ(pipeline::settings_difference(old, pipeline::stage1_settings(job)), "");
    pipeline::FitJob cycled = job;
    cycled.options.exposures = {1.f, 2.f};
    EXPECT_NE(pipeline::settings_difference(old, pipeline::stage1_settings(cycled)).find("exposures"),
              std::string::npos);
    old.erase("emission_decay");
    EXPECT_NE(pipeline::settings_difference(old, pipeline::stage1_settings(job)).find("records no 'emission_decay'"),
              std::string::npos);
}

TEST(Pipeline, EditSequenceRendersEveryFrameOfTheFit) {
    const std::string dir = test::temp_dir("pipeline-edit");
    pipeline::EditJob edit = demo_edit_of_a_small_fit(dir);
    int reported = 0;
    pipeline::Reporter r;
    r.progress = [&](const pipeline::StageProgress& p) {
        reported = p.step;
        return true;
    };
    const int frames = pipeline::render_edits(edit, r);
    EXPECT_EQ(frames, 8);
    EXPECT_EQ(reported, frames);
    for (int i = 0; i < frames; ++i) {
        const Image img = read_image(edit.out + "/frame_000" + std::to_string(i) + "_latent.exr");
        EXPECT_EQ(img.channels, 16);
        EXPECT_EQ(img.width, 8);
    }
}

TEST(Pipeline, ResumedEditsRenderAgainWhenTheFitChanged) {
    // A workflow refits (another seed here) and reruns its edit job with --resume: the frames of
    // the old fit must not be kept; the same fit again keeps them.
    const std::string dir = test::temp_dir("pipeline-edit-refit");
    pipeline::EditJob edit = demo_edit_of_a_small_fit(dir);
    edit.last_frame = 1;
    edit.resume = true;
    pipeline::render_edits(edit);
    const std::string old_latent = read_file(edit.out + "/frame_0001_latent.exr");
    pipeline::FitJob refit = small_fit(dir + "/fit");
    refit.options.seed = 5;
    pipeline::run_fit(refit);
    std::vector<std::string> notes;
    pipeline::Reporter r;
    r.note = [&](const std::string& n) {
        if (n.find("rendering again") != std::string::npos) notes.push_back(n);
    };
    pipeline::render_edits(edit, r);
    ASSERT_EQ(notes.size(), 1u) << "one note naming the first stale frame";
    EXPECT_NE(notes[0].find("frame_0000.done"), std::string::npos) << notes[0];
    pipeline::EditJob fresh = edit;
    fresh.out = dir + "/fresh";
    fresh.resume = false;
    pipeline::render_edits(fresh);
    const std::string new_latent = read_file(edit.out + "/frame_0001_latent.exr");
    EXPECT_NE(new_latent, old_latent) << "the refitted fit's frame was not rendered";
    EXPECT_EQ(new_latent, read_file(fresh.out + "/frame_0001_latent.exr"));
    // Nothing changed since: resume renders nothing (no note, the files stay).
    fs::remove(edit.out + "/frame_0001_latent.exr");
    notes.clear();
    pipeline::render_edits(edit, r);
    EXPECT_TRUE(notes.empty());
    EXPECT_FALSE(fs::exists(edit.out + "/frame_0001_latent.exr")) << "a finished frame was rendered again";
}

/// Every file of `dir` by name, with its bytes.
std::map<std::string, std::string> files_of(const std::string& dir) {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::directory_iterator(dir))
        files[e.path().filename().string()] = read_file(e.path().string());
    return files;
}

// Frame 0 of every sequence shows the training view: with a frame cache the second sequence takes
// its files from the first one's job, byte for byte what rendering it would give; edited frames
// and other settings are never taken from the cache.
TEST(Pipeline, FramesThatShowTheTrainingViewAreRenderedOnceForEverySequence) {
    const std::string dir = test::temp_dir("pipeline-frame-cache");
    pipeline::EditJob first = demo_edit_of_a_small_fit(dir);
    first.last_frame = 1;
    first.reference = true;  // and its scores: metrics_0-1.csv
    first.ref_spp = 4;
    first.frame_cache = dir + "/cache";
    pipeline::render_edits(first);
    // Another sequence: the demo's edits, half as far.
    std::string half = read_file(first.edits);
    half.replace(half.find("[0, 24]"), 7, "[0, 12]");
    pipeline::EditJob second = first;
    second.edits = dir + "/edits-half.json";
    write_text_atomic(second.edits, half);
    second.out = dir + "/second";
    pipeline::render_edits(second);
    pipeline::EditJob uncached = second;
    uncached.out = dir + "/uncached";
    uncached.frame_cache.clear();
    pipeline::render_edits(uncached);
    const std::map<std::string, std::string> got = files_of(second.out), want = files_of(uncached.out);
    EXPECT_TRUE(want.count("metrics_0-1.csv") && want.count("frame_0000_reference.png"));
    for (const auto& [name, bytes] : want) EXPECT_TRUE(got.count(name) && got.at(name) == bytes) << name;
    EXPECT_NE(got.at("frame_0001_latent.exr"), files_of(first.out).at("frame_0001_latent.exr"));
    int entries = 0;
    std::string cached_latent;
    for (const auto& e : fs::directory_iterator(first.frame_cache)) {
        entries += e.path().extension() == ".frame";
        const std::string file = e.path().filename().string();
        if (file.find("_frame_0000.") != std::string::npos && file.size() > 11 &&
            file.compare(file.size() - 11, 11, "_latent.exr") == 0)
            cached_latent = e.path().string();
    }
    EXPECT_EQ(entries, 1) << "frame 1 is edited: only frame 0 is kept";
    ASSERT_FALSE(cached_latent.empty());
    // The second sequence's frame 0 comes from the cache: a changed entry shows in its output.
    fs::copy_file(first.out + "/frame_0001_latent.exr", cached_latent, fs::copy_options::overwrite_existing);
    second.out = dir + "/from-cache";
    pipeline::render_edits(second);
    EXPECT_EQ(read_file(second.out + "/frame_0000_latent.exr"), read_file(cached_latent));
    // Other settings (spp) render their own frame 0 and keep it beside.
    second.spp = 3;
    second.out = dir + "/spp3";
    pipeline::render_edits(second);
    EXPECT_NE(read_file(second.out + "/frame_0000_latent.exr"), read_file(cached_latent));
    entries = 0;
    for (const auto& e : fs::directory_iterator(first.frame_cache)) entries += e.path().extension() == ".frame";
    EXPECT_EQ(entries, 2);
}

// The in-memory session computes exactly what render --edit writes, frame for frame.
TEST(Pipeline, EditSessionFramesEqualTheRenderedFiles) {
    const std::string dir = test::temp_dir("pipeline-session");
    pipeline::FitJob job = small_fit(dir + "/fit");
    job.refiner = true;
    job.refine.train.iterations = 2;
    job.refine.net.expansion = 1;
    pipeline::run_fit(job);
    pipeline::EditJob edit;
    edit.fitdir = dir + "/fit";
    edit.edits = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/edits-demo.json";
    edit.out = dir + "/edit";
    edit.spp = 2;
    edit.seed = 5;
    pipeline::render_edits(edit);
    pipeline::EditSession session(edit.fitdir, edit.edits);
    ASSERT_TRUE(session.has_refiner());
    for (int i : {6, 1}) {  // out of order: each frame depends on its index alone
        const pipeline::FrameLatents f = session.frame(i, 2, 5);
        const std::string stem = edit.out + "/frame_000" + std::to_string(i);
        EXPECT_EQ(f.latent, read_image(stem + "_latent.exr").data) << i;
        EXPECT_EQ(f.refined, read_image(stem + "_refined.exr").data) << i;
    }
    EXPECT_THROW(session.frame(8, 2, 5), std::invalid_argument);
    EXPECT_THROW(session.frame(1, 0, 5), std::invalid_argument);  // was an all-zero latent
    EXPECT_THROW(session.frame(1, 2, 5, -4, 8), std::invalid_argument);
    edit.spp = 0;
    EXPECT_THROW(pipeline::render_edits(edit), std::invalid_argument);  // was eight black frames
}

// Noise views come from the fit folder: more views change what the refiner sees (iteration
// records differ once another view is drawn), the record says how many, and a fit.json that
// cannot say the final render's spp is an error naming the field.
TEST(Pipeline, RefinerNoiseViewsAreRenderedFromTheFit) {
    pipeline::RefineJob r = small_refine(test::temp_dir("pipeline-noise-views"), 12);
    r.train.patience = 0;
    const pipeline::RefineSummary one = pipeline::run_refine(r);
    r.noise_views = 3;
    const pipeline::RefineSummary three = pipeline::run_refine(r);
    EXPECT_EQ(three.metrics["refiner"]["noise_views"], 3);
    ASSERT_EQ(one.result.history.size(), three.result.history.size());
    int differ = 0;
    for (size_t i = 0; i < one.result.history.size(); ++i)
        differ += one.result.history[i].mse != three.result.history[i].mse;
    EXPECT_GT(differ, 0) << "the extra views were never drawn";

    std::string manifest = read_file(r.fitdir + "/fit.json");
    const size_t at = manifest.find("\"final_spp\"");
    ASSERT_NE(at, std::string::npos);
    manifest.replace(at, 11, "\"final_spx\"");
    std::ofstream(r.fitdir + "/fit.json") << manifest;
    test::expect_error_naming([&] { pipeline::run_refine(r); }, {"stage1.final_spp", "fit.json"},
                              "a fit.json without stage1.final_spp was accepted");
}

// Augmented views need the path-traced reference they are encoded from: a fit with a synthetic
// target has none, and asking for them is an error naming the missing file. (Their training is
// tested in tests/refiner, their pixels and the renders they stand for in test_refiner_augment.)
TEST(Pipeline, RefinerAugmentationNeedsThePathTracedReference) {
    pipeline::RefineJob r = small_refine(test::temp_dir("pipeline-augment"), 4);
    r.augment = pipeline::RefinerAugment::Mirror;
    test::expect_error_naming([&] { pipeline::run_refine(r); }, {"reference_rgb.exr", "--refiner-augment mirror"},
                              "augmentation without reference_rgb.exr was accepted");
}

TEST(Pipeline, RefinerResumeRefusesOrRestartsACheckpointOfOtherSettings) {
    // A finished refiner on the cosine, resumed with more iterations (another curve): an error
    // naming refiner_checkpoint.json and the setting; with restart_if_changed a fresh training,
    // equal to one from scratch. (At a constant rate more iterations extend it: tests/cli.)
    pipeline::RefineJob r = small_refine(test::temp_dir("pipeline-refine-changed"), 6);
    r.train.patience = 0;
    r.train.cosine_decay = true;
    pipeline::run_refine(r);
    r.train.iterations = 8;
    r.resume = true;
    test::expect_error_naming([&] { pipeline::run_refine(r); }, {"refiner_checkpoint.json", "iterations"},
                              "resumed a refiner checkpoint trained for another iteration count");
    r.restart_if_changed = true;
    const pipeline::RefineSummary restarted = pipeline::run_refine(r);
    pipeline::RefineJob fresh = r;
    fresh.resume = false;
    const pipeline::RefineSummary scratch = pipeline::run_refine(fresh);
    ASSERT_EQ(restarted.result.history.size(), 8u);
    ASSERT_EQ(scratch.result.history.size(), 8u);
    EXPECT_EQ(restarted.result.history.back().loss, scratch.result.history.back().loss);
    // The same settings resume: nothing is left to train.
    const pipeline::RefineSummary again = pipeline::run_refine(r);
    EXPECT_EQ(again.result.history.size(), 8u);
    EXPECT_EQ(again.result.history.back().loss, scratch.result.history.back().loss);
}

// A refine that could train nothing wrote an untrained refiner.pt with null metrics and exit 0:
// a NaN pixel in the fit folder, a learning rate that overflows the loss, no loss at all.
TEST(Pipeline, ARefinerThatCannotTrainIsAnError) {
    const pipeline::RefineJob good = small_refine(test::temp_dir("pipeline-refine-untrainable"), 3);
    const std::vector<std::pair<std::string, std::function<void(pipeline::RefineJob&)>>> options = {
        {"--w-mse", [](pipeline::RefineJob& r) { r.train.w_mse = std::numeric_limits<float>::infinity(); }},
        {"--w-mse", [](pipeline::RefineJob& r) { r.train.w_mse = 0.f; }},
        {"--expansion", [](pipeline::RefineJob& r) { r.net.expansion = 100000; }},
        {"--noise-views", [](pipeline::RefineJob& r) { r.noise_views = 1000000; }},
    };
    for (const auto& [named, spoil] : options) {
        pipeline::RefineJob r = good;
        spoil(r);
        test::expect_error_naming<std::invalid_argument>([&] { pipeline::run_refine(r); }, {named});
    }
    pipeline::RefineJob huge_lr = good;
    huge_lr.train.lr = 1e30f;
    test::expect_error_naming([&] { pipeline::run_refine(huge_lr); }, {"ruins its own training view"});
    EXPECT_FALSE(fs::exists(good.fitdir + "/refiner.pt"));

    Image target = read_image(good.fitdir + "/target.exr");
    target.data[5] = std::nanf("");
    write_exr(good.fitdir + "/target.exr", target);
    test::expect_error_naming([&] { pipeline::run_refine(good); }, {"target.exr", "not finite"});
    EXPECT_FALSE(fs::exists(good.fitdir + "/refiner.pt"));
}
