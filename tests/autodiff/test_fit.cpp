// The fit recovers parameters from a target the latent renderer made itself, the extra terms do
// not hurt, and a resumed fit ends bit-identical to an uninterrupted one.
#include "autodiff/fit.h"
#include "autodiff/loss.h"
#include "core/scene_loader.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iostream>

using namespace lpt;

namespace {

constexpr int kRes = 16;

Scene cornell() {
    return load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json",
                      {{"camera.width", std::to_string(kRes)},
                       {"camera.height", std::to_string(kRes)},
                       {"integrator.max_depth", "4"}});
}

RenderOptions target_options(const Scene& s, int spp, uint64_t seed) {
    return RenderOptions::from_scene(s, kRes, kRes, spp, seed);
}

FitOptions fit_options(int iterations) {
    FitOptions o;
    o.iterations = iterations;
    o.spp = 4;
    o.seed = 11;
    o.lr = 0.05f;  // small problem, few iterations: the paper's 1e-3 would need thousands
    o.lr_period = iterations;
    o.patience = 0;
    o.reuse_paths = 0;  // fresh paths every iteration unless a test says otherwise
    return o;
}

/// Huber loss against `target` of 4-spp renders of `m` with seeds first_seed … first_seed + 7,
/// averaged: the fit's own sample count, so a perfect fit scores the noise floor.
double loss_at_4spp(const LatentModel& m, const Scene& scene, const std::vector<float>& target, uint64_t first_seed) {
    double loss = 0;
    for (uint64_t s = 0; s < 8; ++s) {
        auto img = render_toned(m, target_options(scene, 4, first_seed + s), ToneCurve::Clip);
        loss += huber_loss(img.data(), target.data(), target.size(), 1.f, nullptr) / 8;
    }
    return loss;
}

}  // namespace

TEST(Fit, RecoversSelfRenderedTargetAndExtraTermsDoNotHurt) {
    // Target: the latent renderer with known random parameters (seed 1), 256 spp.
    Scene target_scene = cornell();
    LatentModel truth(target_scene, Parameterisation::Code, 1);
    const std::vector<float> target = render_toned(truth, target_options(target_scene, 256, 99), ToneCurve::Clip);
    // Noise floor: the true parameters rendered with the fit's spp against the target.
    double floor = loss_at_4spp(truth, target_scene, target, 1000);
    auto run = [&](bool extra_terms, int reuse_paths) {
        Scene scene = cornell();
        LatentModel m(scene, Parameterisation::Code, 2);
        m.terms().ambient = m.terms().occlusion = extra_terms;
        double initial = huber_loss(render_toned(m, target_options(scene, 4, 5), ToneCurve::Clip).data(), target.data(),
                                    target.size(), 1.f, nullptr);
        FitOptions fo = fit_options(400);
        fo.reuse_paths = reuse_paths;
        FitState st = fit_latent(m, target, kRes, kRes, fo);
        double final_loss = loss_at_4spp(m, scene, target, 2000);
        std::cout << (extra_terms ? "Ie+Ia+Ic" : "Ie only") << " (reuse " << reuse_paths << "): initial " << initial
                  << ", final " << final_loss << ", noise floor " << floor << ", skipped steps " << st.skipped_steps
                  << "\n";
        EXPECT_EQ(st.skipped_steps, 0);
        // Without early stopping (patience 0) the kept parameters are the last iteration's.
        EXPECT_EQ(st.best_iteration, fo.iterations - 1);
        EXPECT_EQ(st.best_loss, st.smoothed);
        return std::pair{initial, final_loss};
    };
    auto [init_full, final_full] = run(true, 0);
    auto [init_e, final_e] = run(false, 0);
    // Stored paths replayed for 4 iterations at a time: the same bound (docs/path-replay.md (6)).
    auto [init_reuse, final_reuse] = run(true, 4);
    EXPECT_LT(final_reuse, 3.0 * floor);
    // Recovered: within 3x of the noise floor of a perfect fit (the fit itself is a noisy
    // estimate from 4-spp gradients), and far below where it started.
    EXPECT_LT(final_full, 3.0 * floor);
    EXPECT_LT(final_full, 0.1 * init_full);
    // The target uses all three terms; fitting without Ĩa/Ĩc cannot do better (5% noise margin).
    EXPECT_LE(final_full, 1.05 * final_e);
}

namespace {

/// Fits 30 iterations whole, and again "killed" after iteration 16 with checkpoints every 10
/// (with stored paths: rounded up to a multiple of K), then resumed from the checkpoint.
void expect_resume_bit_identical(int reuse_paths, int expected_next) {
    namespace fs = std::filesystem;
    Scene ts = cornell();
    LatentModel truth(ts, Parameterisation::Paper, 1);
    const std::vector<float> target = render_toned(truth, target_options(ts, 16, 7), ToneCurve::Clip);
    const std::string dir = test::write_temp_file("resume/placeholder", "");
    const std::string ckpt = fs::path(dir).parent_path().string() + "/ckpt" + std::to_string(reuse_paths);
    fs::remove_all(ckpt);

    Scene s1 = cornell();
    LatentModel full(s1, Parameterisation::Paper, 2);
    FitOptions o = fit_options(30);
    o.patience = 5;  // early-stopping state must survive the restart too
    o.reuse_paths = reuse_paths;
    FitState whole = fit_latent(full, target, kRes, kRes, o);

    Scene s2 = cornell();
    LatentModel part(s2, Parameterisation::Paper, 2);
    FitOptions killed = o;
    killed.checkpoint_every = 10;
    killed.checkpoint_dir = ckpt;
    fit_latent(part, target, kRes, kRes, killed, {},
               [](const FitRecord& r, const FitState&) { return r.iteration < 16; });
    Scene s3 = cornell();
    LatentModel resumed(s3, Parameterisation::Paper, 99);  // different init: the checkpoint must overwrite it
    FitState st = load_checkpoint(ckpt, resumed);
    EXPECT_EQ(st.next_iteration, expected_next);
    FitState rest = fit_latent(resumed, target, kRes, kRes, o, st);
    EXPECT_EQ(rest.history.size(), whole.history.size());
    EXPECT_EQ(rest.history.back().loss, whole.history.back().loss);
    EXPECT_EQ(resumed.params().raw(), full.params().raw());
}

}  // namespace

TEST(Fit, ResumedFitEndsBitIdentical) { expect_resume_bit_identical(0, 10); }

TEST(Fit, ResumedFitWithStoredPathsEndsBitIdentical) { expect_resume_bit_identical(4, 12); }

// A fit that stopped early and is resumed from its state (a run killed after stage 1) takes no
// further step: it returns what the uninterrupted fit returned.
TEST(Fit, AnEarlyStoppedFitStaysStoppedWhenResumed) {
    Scene ts = cornell();
    LatentModel truth(ts, Parameterisation::Paper, 1);
    const std::vector<float> target = render_toned(truth, target_options(ts, 16, 7), ToneCurve::Clip);
    Scene s = cornell();
    LatentModel m(s, Parameterisation::Paper, 2);
    FitOptions o = fit_options(30);
    o.patience = 1;
    o.min_delta = 1e9f;  // only the first update improves: it stops after two iterations
    const FitState stopped = fit_latent(m, target, kRes, kRes, o);
    ASSERT_EQ(stopped.history.size(), 2u);
    const std::vector<float> raw = m.params().raw();
    const FitState again = fit_latent(m, target, kRes, kRes, o, stopped);
    EXPECT_EQ(again.history.size(), 2u);
    EXPECT_EQ(again.next_iteration, stopped.next_iteration);
    EXPECT_EQ(m.params().raw(), raw);
}

TEST(Fit, RejectsNonFiniteOrMisshapenTargets) {
    Scene s = cornell();
    LatentModel m(s, Parameterisation::Code, 1);
    std::vector<float> t(size_t(kRes) * kRes * kLatentChannels, 0.f);
    t[37] = std::nanf("");
    test::expect_error_naming<std::invalid_argument>([&] { fit_latent(m, t, kRes, kRes, fit_options(1)); },
                                                     {"channel 5"}, "a NaN in the target was accepted");
    EXPECT_THROW(fit_latent(m, std::vector<float>(10), kRes, kRes, fit_options(1)), std::invalid_argument);
}

// A step whose gradient is not finite is refused and named; the parameters stay as they were.
// Injected: an emitter so bright (1e25, reachable by the paper's pos - neg map) that the
// reflectance gradients' squares overflow float.
TEST(Fit, NonFiniteStepsAreRefusedNamedAndLeaveTheParameters) {
    Scene scene = cornell();
    LatentModel m(scene, Parameterisation::Paper, 2);
    const int le = m.params().find("light.Le");
    ASSERT_GE(le, 0);
    const std::vector<float> bright(kLatentChannels, 1e25f);
    m.params().set_value(le, bright.data());
    m.sync();
    const std::vector<float> raw_before = m.params().raw();
    const std::vector<float> target(size_t(kRes) * kRes * kLatentChannels, 0.f);
    FitOptions o = fit_options(3);
    o.tone = ToneCurve::None;  // the Huber loss bounds dloss/dlatent; the size comes from L̃e
    const FitState st = fit_latent(m, target, kRes, kRes, o);
    ASSERT_EQ(st.history.size(), 3u);
    for (const FitRecord& r : st.history) {
        EXPECT_TRUE(r.refused) << r.iteration;
        EXPECT_GE(m.params().find(r.refused_parameter), 0) << "'" << r.refused_parameter << "' is not a slice";
    }
    EXPECT_EQ(st.skipped_steps, 3);
    EXPECT_EQ(m.params().raw(), raw_before);
}

namespace {

/// A penalty's raw gradient (value gradient mapped by ParamStore::backward) against central
/// differences of the penalty itself, for the identity, pos − neg and gain maps; the slices
/// `penalised` names must have gradients, all others none.
void expect_penalty_gradient_matches_differences(const std::function<double(ParamStore&)>& penalty,
                                                 const std::function<bool(const ParamSlice&)>& penalised) {
    for (Parameterisation p : {Parameterisation::Code, Parameterisation::Paper, Parameterisation::Gain}) {
        Scene scene = cornell();
        LatentModel m(scene, p, 3);
        ParamStore& ps = m.params();
        const int le = ps.find("light.Le");
        if (ps.slice(le).map == ParamMap::Gain) {  // a log-gain away from 0, where ∂v/∂u = e^g ≠ 1
            ps.raw()[ps.slice(le).raw_offset + ps.slice(le).channels] = 0.4f;
            ps.update_values();
        }
        ps.zero_grad();
        const double at = penalty(ps);
        ps.backward();
        const std::vector<float> grad = ps.grad_raw();
        EXPECT_GT(at, 0.0);
        int checked = 0, penalised_entries = 0;
        for (size_t k = 0; k < ps.slice_count(); ++k) {
            const ParamSlice& sl = ps.slice(int(k));
            for (size_t r = sl.raw_offset; r < sl.raw_offset + sl.raw_size(); ++r) {
                const float h = 1e-2f, keep = ps.raw()[r];
                auto penalty_at = [&](float x) {
                    ps.raw()[r] = x;
                    ps.update_values();
                    ps.zero_grad();
                    return penalty(ps);
                };
                const double fd = (penalty_at(keep + h) - penalty_at(keep - h)) / (2 * h);
                penalty_at(keep);
                // Quadratic in the values, values affine in raw: exact up to rounding; the gain's
                // e^(2g) makes the central difference off by (2h)²/6 relatively, inside the margin.
                EXPECT_NEAR(grad[r], fd, 1e-4 + 1e-3 * std::abs(fd)) << sl.name << " raw " << r - sl.raw_offset;
                if (penalised(sl)) ++penalised_entries;
                else EXPECT_EQ(grad[r], 0.f) << sl.name;
                ++checked;
            }
        }
        EXPECT_GT(penalised_entries, 0);
        EXPECT_EQ(size_t(checked), ps.raw().size());
    }
}

}  // namespace

TEST(EmissionDecay, GradientMatchesCentralDifferencesInEveryParameterisation) {
    expect_penalty_gradient_matches_differences([](ParamStore& ps) { return add_emission_decay(ps, 0.3f); },
                                                [](const ParamSlice& sl) { return sl.kind == "Le"; });
}

TEST(EmitterResponseDecay, GradientMatchesCentralDifferencesOnTheLightsResponsesOnly) {
    // The Cornell box's one emitting shape is "light": its La and Lc are penalised, no other
    // shape's (the walls' responses are what carries them) and no Le.
    expect_penalty_gradient_matches_differences(
        [](ParamStore& ps) { return add_emitter_response_decay(ps, 0.3f); },
        [](const ParamSlice& sl) { return sl.name == "light.La" || sl.name == "light.Lc"; });
}

namespace {

struct DecayedFit {
    double le2 = 0, light_responses2 = 0, loss = 0;  ///< Σ L̃e², Σ (L̃a² + L̃c²) of the light, loss at 4 spp
};

/// A 300-iteration fit of all three terms, to a target rendered by another random model.
DecayedFit fit_with_decay(float emission_decay, float emitter_response_decay) {
    Scene ts = cornell();
    LatentModel truth(ts, Parameterisation::Code, 1);
    const std::vector<float> target = render_toned(truth, target_options(ts, 256, 99), ToneCurve::Clip);
    Scene scene = cornell();
    LatentModel m(scene, Parameterisation::Code, 2);
    m.terms().ambient = true;
    FitOptions fo = fit_options(300);
    fo.emission_decay = emission_decay;
    fo.emitter_response_decay = emitter_response_decay;
    fit_latent(m, target, kRes, kRes, fo);
    DecayedFit r;
    const ParamStore& ps = m.params();
    for (size_t k = 0; k < ps.slice_count(); ++k)
        for (int c = 0; c < ps.slice(int(k)).channels; ++c) {  // scalar slices have one value
            const double v2 = std::pow(ps.value(int(k))[c], 2.0);
            if (ps.slice(int(k)).kind == "Le") r.le2 += v2;
            if (ps.slice(int(k)).name == "light.La" || ps.slice(int(k)).name == "light.Lc") r.light_responses2 += v2;
        }
    r.loss = loss_at_4spp(m, scene, target, 3000);
    std::cout << "decays " << emission_decay << ", " << emitter_response_decay << ": sum Le^2 " << r.le2
              << ", light La^2 + Lc^2 " << r.light_responses2 << ", loss " << r.loss << "\n";
    return r;
}

}  // namespace

TEST(EmissionDecay, PullsTheLightOutOfTheFlatTermsValley) {
    // With the flat term on, the light's own pixels see L̃e + L̃a only; the penalty must shrink
    // |L̃e| (the part that also lights the room, with the room's noise) at little cost in loss.
    const DecayedFit free = fit_with_decay(0.f, 0.f), decayed = fit_with_decay(1e-3f, 0.f);
    EXPECT_LT(decayed.le2, 0.5 * free.le2);
    EXPECT_LT(decayed.loss, 1.5 * free.loss);
}

TEST(EmitterResponseDecay, PinsTheLightsResponsesNotItsEmission) {
    // The same valley closed from the other side: the light's L̃a and L̃c go to ~0, so its own
    // pixels fix L̃e, which the penalty leaves alone (unlike the emission decay, it may stay large).
    const DecayedFit free = fit_with_decay(0.f, 0.f), pinned = fit_with_decay(0.f, 1e-3f);
    EXPECT_LT(pinned.light_responses2, 0.25 * free.light_responses2);
    EXPECT_GT(pinned.le2, 0.5 * free.le2);
    EXPECT_LT(pinned.loss, 1.5 * free.loss);
}

TEST(Fit, GainReachesALightFarBeyondTheCodeClamp) {
    // Target: Ĩe of a model whose light is 40x a vector inside [-1, 1], far past Code's [-6, 6]
    // (more than the reflectances, at most 1 instead of the truth's ~0.5, can make up for).
    Scene ts = cornell();
    LatentModel truth(ts, Parameterisation::Gain, 1);
    const int le = truth.params().find("light.Le");
    std::vector<float> bright(kLatentChannels);
    for (int c = 0; c < kLatentChannels; ++c) bright[c] = 40.f * (c % 2 ? -1.f : 1.f) * (0.5f + 0.03f * c);
    truth.params().set_value(le, bright.data());
    truth.sync();
    truth.terms().ambient = truth.terms().occlusion = false;  // only L̃e can make the room bright
    const std::vector<float> target = render_toned(truth, target_options(ts, 256, 99), ToneCurve::Clip);
    double floor = loss_at_4spp(truth, ts, target, 4000);
    auto fit = [&](Parameterisation p) {
        Scene scene = cornell();
        LatentModel m(scene, p, 2);
        m.terms().ambient = m.terms().occlusion = false;
        fit_latent(m, target, kRes, kRes, fit_options(300));
        double loss = loss_at_4spp(m, scene, target, 4000);
        const float gain = m.params().value(le)[0] / bright[0];
        std::cout << (p == Parameterisation::Gain ? "gain" : "code") << ": loss " << loss << " (floor " << floor
                  << "), light channel 0 at " << gain << " of the truth's\n";
        return std::pair{loss, gain};
    };
    const auto [code_loss, code_ratio] = fit(Parameterisation::Code);
    const auto [gain_loss, gain_ratio] = fit(Parameterisation::Gain);
    EXPECT_GT(gain_ratio, 6.f / bright[0]);  // grown past what the clamp lets code reach (code_ratio)
    EXPECT_LT(gain_loss, 1.2 * floor);       // recovered: at the noise floor
    EXPECT_GT(code_loss, 2.0 * floor);       // cannot get there
}
