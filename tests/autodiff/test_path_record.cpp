// Stored-path replay (autodiff/path_record.h): the records replay the primal and the retracing
// adjoint exactly, and after a parameter change they still give the primal of the new
// parameters (the same paths), which is what `fit --reuse-paths K` relies on. Scene: the
// Cornell box with every BSDF family the sweep treats differently — delta only (mirror, glass),
// delta + non-delta (smooth plastic), rough (GGX conductor, rough plastic, rough dielectric).
#include "autodiff/latent_path_adjoint.h"
#include "autodiff/path_record.h"
#include "core/sampler.h"
#include "core/scene_loader.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <cmath>
#include <stdexcept>

using namespace lpt;

namespace {

Scene mixed_cornell() {
    // Russian roulette off: its survival probability depends on |β|, so a parameter change
    // would change which paths exist (fit --reuse-paths keeps q as recorded instead).
    Scene s =
        load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json", {{"camera.width", "12"},
                                                                                    {"camera.height", "12"},
                                                                                    {"integrator.max_depth", "6"},
                                                                                    {"integrator.rr_depth", "100"}});
    auto assign = [&](const std::string& shape, const std::string& type, float alpha) {
        Props p;
        p.type = type;
        p.file = "test";
        if (alpha > 0) p.values["alpha"] = alpha;
        s.materials.push_back(p);
        const int id = s.find_shape(shape);
        if (id < 0) throw std::logic_error("the bundled Cornell box has no shape " + shape);
        s.shapes[id].material = int(s.materials.size()) - 1;
    };
    assign("tall_block", "conductor", 0);
    assign("short_block", "dielectric", 0);
    assign("back", "plastic", 0);
    assign("red_wall", "roughconductor", 0.2f);
    assign("green_wall", "roughplastic", 0.3f);
    assign("ceiling", "roughdielectric", 0.25f);
    return s;
}

RenderOptions opts(const Scene& s) {
    RenderOptions o = RenderOptions::from_scene(s);
    o.spp = 8;
    o.seed = 11;
    return o;
}

std::vector<float> weights(size_t n) { return test::random_weights(n, 5); }

double max_rel_diff(const std::vector<float>& a, const std::vector<float>& b) {
    double scale = 0, diff = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        scale = std::max(scale, double(std::abs(b[i])));
        diff = std::max(diff, double(std::abs(a[i] - b[i])));
    }
    return diff / std::max(scale, 1e-30);
}

}  // namespace

TEST(PathRecord, ReplaysPrimalAndRetracingAdjoint) {
    Scene scene = mixed_cornell();
    LatentModel m(scene, Parameterisation::Code, 3);
    const RenderOptions o = opts(scene);
    const std::vector<float> w = weights(size_t(scene.camera.width) * scene.camera.height * kLatentChannels);
    std::vector<float> recorded_image;
    PathRecords records = record_latent_paths(m, o, &recorded_image);
    const std::vector<float> primal = render_latent_terms<kLatentChannels>(m.scene(), m.spectra(), m.terms(), o).sum();
    EXPECT_EQ(recorded_image, primal) << "recording must not change the render";
    EXPECT_GT(records.events(), size_t(scene.camera.width * scene.camera.height * o.spp));
    // The forward sweep recomputes every BSDF value; rounding differs from the tracer's order.
    EXPECT_LT(max_rel_diff(replay_forward(m, records), primal), 1e-5);

    m.params().zero_grad();
    backward_latent(m, o, w);
    const std::vector<float> retraced = m.params().grad_values();
    m.params().zero_grad();
    replay_backward(m, records, w);
    EXPECT_EQ(m.params().grad_values(), retraced) << "same blocks, same sweep, same tile order";
    double norm = 0;
    for (float g : retraced) norm += std::abs(g);
    EXPECT_GT(norm, 1e-3);
}

TEST(PathRecord, RecordsStayValidAfterParameterSteps) {
    Scene scene = mixed_cornell();
    LatentModel m(scene, Parameterisation::Code, 4);
    const RenderOptions o = opts(scene);
    PathRecords records = record_latent_paths(m, o);
    // Move every spectral value (the optimiser's job) but no roughness: sampling depends on alpha.
    ParamStore& ps = m.params();
    for (size_t si = 0; si < ps.slice_count(); ++si) {
        const ParamSlice& sl = ps.slice(int(si));
        if (sl.channels != kLatentChannels) continue;
        std::vector<float> v(ps.value(int(si)), ps.value(int(si)) + sl.channels);
        for (int c = 0; c < sl.channels; ++c)
            v[c] = sl.kind == "reflectance" ? 0.2f + 0.6f * sample_1d(9, uint32_t(si), uint32_t(c), 0)
                                            : 2.f * sample_1d(9, uint32_t(si), uint32_t(c), 1) - 1.f;
        ps.set_value(int(si), v.data());
    }
    m.sync();
    const std::vector<float> primal = render_latent_terms<kLatentChannels>(m.scene(), m.spectra(), m.terms(), o).sum();
    const std::vector<float> replayed = replay_forward(m, records);
    EXPECT_LT(max_rel_diff(replayed, primal), 1e-5) << "the stored paths are those of the new parameters too";
    const std::vector<float> w = weights(primal.size());
    m.params().zero_grad();
    backward_latent(m, o, w);
    const std::vector<float> retraced = m.params().grad_values();
    m.params().zero_grad();
    replay_backward(m, records, w);
    EXPECT_LT(max_rel_diff(m.params().grad_values(), retraced), 1e-5);
}

TEST(PathRecord, BackwardIndependentOfThreadsAndRejectsWrongShape) {
    Scene scene = mixed_cornell();
    LatentModel m(scene, Parameterisation::Paper, 5);
    const RenderOptions o = opts(scene);
    PathRecords records = record_latent_paths(m, o);
    const std::vector<float> w = weights(size_t(scene.camera.width) * scene.camera.height * kLatentChannels);
    std::vector<float> g1;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        m.params().zero_grad();
        replay_backward(m, records, w);
        g1 = m.params().grad_values();
    }
    m.params().zero_grad();
    replay_backward(m, records, w);
    EXPECT_EQ(m.params().grad_values(), g1);
    EXPECT_THROW(replay_backward(m, records, std::vector<float>(7)), std::invalid_argument);
}

// Two recorders taking turns on one thread (a fit inside a fit, two models) each keep their own
// wavefront: the per-thread state belongs to the recorder, not to the class.
TEST(PathRecorder, TwoRecordersOnOneThreadKeepTheirOwnEvents) {
    detail::PathRecorder a(1), b(1);
    a.begin(0, 1);
    b.begin(0, 1);
    a.emission(0, 3, 0.5f);
    b.ambient(0, 7);
    b.ambient(0, 8);
    const uint32_t pixel = 0, sample = 0;
    a.end(&pixel, &sample, 1);
    b.end(&pixel, &sample, 1);
    ASSERT_EQ(a.records()[0].size(), 1u);
    ASSERT_EQ(b.records()[0].size(), 1u);
    const PathBlock &ra = a.records()[0][0], &rb = b.records()[0][0];
    ASSERT_EQ(ra.events.size(), 1u);
    EXPECT_EQ(ra.events[0].type, PathEvent::Emission);
    EXPECT_EQ(ra.events[0].emitter, 3);
    ASSERT_EQ(rb.events.size(), 2u);
    EXPECT_EQ(rb.events[1].shape, 8);
}

// Attaching the recorder must not change what the primal renders or traces: with a reflectance at
// exactly zero (whose derivative is not zero), the latent render keeps those paths either way.
TEST(PathRecord, AnObserverDoesNotChangeThePrimal) {
    Scene scene = mixed_cornell();
    LatentModel m(scene, Parameterisation::Paper, 3);
    const int floor = scene.find_shape("floor");
    ASSERT_FALSE(m.slots(floor).bsdf.empty());
    const std::vector<float> zero(kLatentChannels, 0.f);
    m.params().set_value(m.slots(floor).bsdf.front().second, zero.data());
    m.sync();
    const RenderOptions o = opts(scene);
    RenderStats plain_stats, recorded_stats;
    const std::vector<float> plain =
        render_latent_terms<kLatentChannels>(scene, m.spectra(), m.terms(), o, &plain_stats).sum();
    std::vector<float> recorded;
    record_latent_paths(m, o, &recorded, &recorded_stats);
    ASSERT_EQ(plain.size(), recorded.size());
    for (size_t i = 0; i < plain.size(); ++i) ASSERT_EQ(plain[i], recorded[i]) << "value " << i;
    EXPECT_EQ(plain_stats.shadow_rays, recorded_stats.shadow_rays);
    EXPECT_EQ(plain_stats.extension_rays, recorded_stats.extension_rays);
}
