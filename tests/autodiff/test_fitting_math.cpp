// Fitting math against hand values and central finite differences: tone curves, losses, Adam,
// SGDR and early stopping (docs/fitting.md (1)–(16)).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "autodiff/adam.h"
#include "autodiff/loss.h"
#include "autodiff/lr_schedule.h"
#include "autodiff/tone_curve.h"

namespace lpt {
namespace {

const double k_gamma = 1.0 / 2.2;
const float k_nan = std::numeric_limits<float>::quiet_NaN();
const float k_inf = std::numeric_limits<float>::infinity();

// ---- tone curve ----------------------------------------------------------------------------

TEST(ToneCurve, HandValues) {
    EXPECT_FLOAT_EQ(tone(ToneCurve::Clip, 1.0f), 3.0f);
    EXPECT_FLOAT_EQ(tone(ToneCurve::Clip, 5.0f), float(3.0 * std::pow(3.0, k_gamma)));
    EXPECT_FLOAT_EQ(tone(ToneCurve::Clip, 3.0f), tone(ToneCurve::Clip, 100.0f));
    EXPECT_FLOAT_EQ(tone(ToneCurve::Clip, 0.25f), float(3.0 * std::pow(0.25, k_gamma)));
    EXPECT_FLOAT_EQ(tone(ToneCurve::Reinhard, 1.0f), float(4.0 * std::pow(0.5, k_gamma)));
    EXPECT_FLOAT_EQ(tone(ToneCurve::Reinhard, 3.0f), float(4.0 * std::pow(0.75, k_gamma)));
    EXPECT_FLOAT_EQ(tone(ToneCurve::None, -1.5f), -1.5f);
    for (ToneCurve c : {ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::None}) EXPECT_EQ(tone(c, 0.0f), 0.0f);
}

// The baseline's logit: hand values, the clamp, and its derivative (exact inside, 0 outside).
TEST(ToneCurve, LogitBaseline) {
    EXPECT_FLOAT_EQ(tone(ToneCurve::Logit, 0.5f), 0.0f);
    EXPECT_NEAR(tone(ToneCurve::Logit, 0.75f), std::log(3.0f), 1e-6f);
    EXPECT_NEAR(tone(ToneCurve::Logit, 0.0f), std::log(k_logit_eps / (1 - k_logit_eps)), 1e-4f);
    EXPECT_EQ(tone(ToneCurve::Logit, -2.0f), tone(ToneCurve::Logit, 0.0f));
    EXPECT_EQ(tone(ToneCurve::Logit, 7.0f), tone(ToneCurve::Logit, 1.0f));
    for (float x : {0.01f, 0.2f, 0.5f, 0.9f, 0.99f}) {
        const float h = 1e-3f * std::min(x, 1 - x);
        const double fd = (double(tone(ToneCurve::Logit, x + h)) - double(tone(ToneCurve::Logit, x - h))) / (2.0 * h);
        EXPECT_NEAR(d_tone(ToneCurve::Logit, x), fd, 3e-3 * fd) << x;  // float rounding of 1 − y near 1
    }
    EXPECT_EQ(d_tone(ToneCurve::Logit, 0.0f), 0.0f);  // the clamp holds: no slope
    EXPECT_EQ(d_tone(ToneCurve::Logit, 1.5f), 0.0f);
    EXPECT_EQ(parse_tone_curve("logit"), ToneCurve::Logit);
}

TEST(ToneCurve, OddValueEvenDerivative) {
    for (ToneCurve c : {ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::None})
        for (float x : {1e-5f, 1e-4f, 0.3f, 1.0f, 2.9f, 3.0f, 4.2f, 50.0f}) {
            EXPECT_EQ(tone(c, -x), -tone(c, x)) << to_string(c) << " x=" << x;
            EXPECT_EQ(d_tone(c, -x), d_tone(c, x)) << to_string(c) << " x=" << x;
        }
}

TEST(ToneCurve, InverseUndoesTheCurveAndClampsToItsRange) {
    for (ToneCurve c : {ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::None, ToneCurve::Logit})
        for (float x : {1e-3f, 0.05f, 0.3f, 1.0f, 2.9f}) {
            const float xs = c == ToneCurve::Logit ? x / 3.f : x;  // logit's domain is (0, 1)
            for (float v : {xs, c == ToneCurve::Logit ? xs : -xs})
                EXPECT_NEAR(tone_inverse(c, tone(c, v)), v, 2e-5f * std::max(1.f, std::abs(v)))
                    << to_string(c) << " x=" << v;
        }
    // past the curve's range: the end of the domain that T maps furthest
    EXPECT_EQ(tone_inverse(ToneCurve::Clip, 6.f), 3.f);
    EXPECT_EQ(tone_inverse(ToneCurve::Clip, -6.f), -3.f);
    EXPECT_GT(tone_inverse(ToneCurve::Reinhard, 5.f), 1e3f);
    EXPECT_TRUE(std::isfinite(tone_inverse(ToneCurve::Reinhard, 5.f)));
    EXPECT_NEAR(tone_inverse(ToneCurve::Logit, 40.f), 1.f - k_logit_eps, 1e-7f);
}

// Float evaluations, differenced in double with a step relative to |x|: the rounding error
// (~6e-8 · |T| / h) and truncation error (~0.14 (h/x)²) both stay near 1e-5.
TEST(ToneCurve, DerivativeMatchesCentralDifferences) {
    std::vector<float> xs;
    for (int i = 0; i <= 876; ++i) xs.push_back(-6.0f + 0.0137f * float(i));
    for (int i = 0; i <= 30; ++i) {
        const float a = float(std::pow(10.0, -3.0 + 0.1 * i));
        xs.push_back(a);
        xs.push_back(-a);
    }
    int checked = 0;
    for (ToneCurve c : {ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::None})
        for (float x : xs) {
            const float a = std::fabs(x);
            const float h = 0.01f * a;
            if (a < 1e-3f || (c == ToneCurve::Clip && std::fabs(a - 3.0f) < 3.0f * h)) continue;
            const float xp = x + h, xm = x - h;
            const double fd = (double(tone(c, xp)) - double(tone(c, xm))) / (double(xp) - double(xm));
            const double d = d_tone(c, x);
            EXPECT_NEAR(d, fd, 1e-3 * std::max(std::fabs(fd), 1e-3)) << to_string(c) << " x=" << x;
            ++checked;
        }
    EXPECT_GT(checked, 2000);
    EXPECT_EQ(d_tone(ToneCurve::Clip, 3.5f), 0.0f);
    EXPECT_GT(d_tone(ToneCurve::Clip, 3.0f), 0.0f);  // left slope kept at the kink, like torch.clamp
}

TEST(ToneCurve, DerivativeFiniteAtZero) {
    const float eps = k_tone_grad_eps;
    for (ToneCurve c : {ToneCurve::Clip, ToneCurve::Reinhard}) {
        const float at_eps = d_tone(c, eps);
        for (float x : {0.0f, -0.0f, eps, -eps, 0.5f * eps, -1e-30f}) {
            EXPECT_TRUE(std::isfinite(d_tone(c, x))) << to_string(c) << " x=" << x;
            EXPECT_EQ(d_tone(c, x), at_eps) << to_string(c) << " x=" << x;
        }
        EXPECT_NEAR(d_tone(c, 1.001f * eps), at_eps, 1e-3 * at_eps);  // continuous at eps
        EXPECT_GT(d_tone(c, eps), d_tone(c, 10.0f * eps));            // still the steep part
    }
    EXPECT_NEAR(d_tone(ToneCurve::Clip, 0.0f), 3.0 * k_gamma * std::pow(1e-4, k_gamma - 1.0), 0.05);
}

TEST(ToneCurve, VectorisedMatchesScalarInPlace) {
    std::vector<float> x = {-7.0f, -3.0f, -0.4f, 0.0f, 2e-5f, 0.9f, 3.1f, 12.0f};
    std::vector<float> g = {1.0f, -2.0f, 0.5f, 3.0f, -1.0f, 0.25f, 4.0f, -0.1f};
    for (ToneCurve c : {ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::None}) {
        std::vector<float> y(x.size()), d_in = g;
        tone_map(c, x.data(), y.data(), x.size());
        tone_map_backward(c, x.data(), d_in.data(), d_in.data(), x.size());  // aliased d_out/d_in
        for (size_t i = 0; i < x.size(); ++i) {
            EXPECT_EQ(y[i], tone(c, x[i]));
            EXPECT_EQ(d_in[i], g[i] * d_tone(c, x[i]));
        }
    }
}

TEST(ToneCurve, ParsesNamesAndRejectsOthers) {
    EXPECT_EQ(parse_tone_curve("clip"), ToneCurve::Clip);
    EXPECT_EQ(parse_tone_curve("reinhard"), ToneCurve::Reinhard);
    EXPECT_EQ(parse_tone_curve("none"), ToneCurve::None);
    for (ToneCurve c : {ToneCurve::Clip, ToneCurve::Reinhard, ToneCurve::None})
        EXPECT_EQ(parse_tone_curve(to_string(c)), c);
    for (const char* bad : {"", "Clip", "gamma", "reinhard "})
        EXPECT_THROW(parse_tone_curve(bad), std::invalid_argument) << bad;
}

// ---- losses -------------------------------------------------------------------------------

TEST(HuberLoss, QuadraticAndLinearRegions) {
    const std::vector<float> t = {0.0f, 1.0f, -2.0f, 0.5f};
    const std::vector<float> quad = {0.5f, 0.75f, -1.9f, -0.4f};  // r = .5, -.25, .1, -.9
    EXPECT_NEAR(huber_loss(quad.data(), t.data(), 4), 0.5 * (0.25 + 0.0625 + 0.01 + 0.81) / 4, 1e-7);
    const std::vector<float> lin = {2.0f, -2.5f, 1.0f, 0.5f};  // r = 2, -3.5, 3, 0
    EXPECT_NEAR(huber_loss(lin.data(), t.data(), 4), (1.5 + 3.0 + 2.5 + 0.0) / 4, 1e-7);
    // delta = 0.5: r = 2 → 0.5 (2 − 0.25); r = 0.25 → 0.5 · 0.0625
    const std::vector<float> p2 = {2.0f, 1.25f}, t2 = {0.0f, 1.0f};
    std::vector<float> d(2);
    EXPECT_NEAR(huber_loss(p2.data(), t2.data(), 2, 0.5f, d.data()), (0.875 + 0.03125) / 2, 1e-7);
    EXPECT_FLOAT_EQ(d[0], 0.25f);   // δ sign(r) / n
    EXPECT_FLOAT_EQ(d[1], 0.125f);  // r / n
}

// Both losses are piecewise quadratic, so central differences are exact away from |r| = δ.
TEST(HuberLoss, GradientMatchesCentralDifferences) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-3.0f, 3.0f);
    const size_t n = 64;
    std::vector<float> pred(n), target(n), d_huber(n), d_mse(n);
    for (size_t i = 0; i < n; ++i) {
        target[i] = u(rng);
        do pred[i] = u(rng);
        while (std::fabs(std::fabs(pred[i] - target[i]) - 1.0f) < 0.01f);
    }
    huber_loss(pred.data(), target.data(), n, 1.0f, d_huber.data());
    mse_loss(pred.data(), target.data(), n, d_mse.data());
    const float h = 1.0f / 1024.0f;  // exact in float for |pred| < 4
    for (size_t i = 0; i < n; ++i) {
        std::vector<float> p = pred, m = pred;
        p[i] += h;
        m[i] -= h;
        const double fd_h = (huber_loss(p.data(), target.data(), n) - huber_loss(m.data(), target.data(), n)) / (2 * h);
        const double fd_m = (mse_loss(p.data(), target.data(), n) - mse_loss(m.data(), target.data(), n)) / (2 * h);
        EXPECT_NEAR(d_huber[i], fd_h, 1e-6) << i;
        EXPECT_NEAR(d_mse[i], fd_m, 1e-6) << i;
    }
}

TEST(HuberLoss, NanResidualGivesNanGradientAndBadInputsThrow) {
    const std::vector<float> p = {k_nan, 1.0f}, t = {0.0f, 0.0f};
    std::vector<float> d(2);
    EXPECT_TRUE(std::isnan(huber_loss(p.data(), t.data(), 2, 1.0f, d.data())));
    EXPECT_TRUE(std::isnan(d[0]));
    EXPECT_THROW(huber_loss(p.data(), t.data(), 0), std::invalid_argument);
    EXPECT_THROW(huber_loss(p.data(), t.data(), 2, 0.0f), std::invalid_argument);
    EXPECT_THROW(mse_loss(p.data(), t.data(), 0), std::invalid_argument);
    EXPECT_EQ(mse_loss(p.data() + 1, t.data() + 1, 1), 1.0);
}

TEST(CheckFinite, ReportsFirstNonFiniteIndex) {
    const std::vector<float> ok = {0.0f, -1e30f, 5.0f}, bad = {1.0f, 2.0f, k_inf, k_nan};
    size_t idx = 99;
    EXPECT_TRUE(check_finite(ok.data(), ok.size(), &idx));
    EXPECT_EQ(idx, 99u);
    EXPECT_FALSE(check_finite(bad.data(), bad.size(), &idx));
    EXPECT_EQ(idx, 2u);
    EXPECT_FALSE(check_finite(bad.data() + 3, 1, &idx));
    EXPECT_EQ(idx, 0u);
}

// ---- Adam ---------------------------------------------------------------------------------

TEST(Adam, FirstStepMovesByLrTimesSign) {
    std::vector<float> p = {0.0f, 1.0f, -2.0f, 0.5f, 3.0f, 7.0f}, g = {0.3f, -5.0f, 1e-3f, 100.0f, -1e-2f, 0.0f};
    const std::vector<float> p0 = p;
    Adam adam(p.size());
    const float lr = 1e-2f;
    EXPECT_EQ(adam.step(p.data(), g.data(), p.size(), lr), 0u);
    for (size_t i = 0; i < p.size(); ++i) {
        const float expected = g[i] > 0 ? -lr : (g[i] < 0 ? lr : 0.0f);
        EXPECT_NEAR(p[i] - p0[i], expected, 1e-6) << i;
    }
    EXPECT_EQ(adam.state().step, 1);
}

TEST(Adam, MinimisesQuadratic) {
    // f(p) = ½ Σ a_i (p_i − c_i)², curvatures over four decades, lr annealed by one SGDR cycle.
    const std::vector<double> a = {1.0, 10.0, 0.1, 100.0}, c = {1.0, -2.0, 0.5, 3.0};
    std::vector<float> p(4, 0.0f), g(4);
    Adam adam(4);
    const CosineWarmRestarts lr(0.05f, 3000);
    for (int it = 0; it < 3000; ++it) {
        for (size_t i = 0; i < 4; ++i) g[i] = float(a[i] * (p[i] - c[i]));
        ASSERT_EQ(adam.step(p.data(), g.data(), 4, lr.lr_at(it)), 0u);
    }
    for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(p[i], c[i], 1e-3) << i;
}

TEST(Adam, NonFiniteGradientLeavesEverythingUntouched) {
    std::vector<float> p = {1.0f, 2.0f, 3.0f, 4.0f}, g = {0.5f, -1.0f, 2.0f, 0.1f};
    Adam adam(4);
    adam.step(p.data(), g.data(), 4, 0.1f);
    const std::vector<float> p_before = p;
    const AdamState s_before = adam.state();
    const std::vector<float> bad = {k_nan, 1.0f, k_inf, -k_inf};
    EXPECT_EQ(adam.step(p.data(), bad.data(), 4, 0.1f), 3u);
    EXPECT_EQ(std::memcmp(p.data(), p_before.data(), 4 * sizeof(float)), 0);
    EXPECT_EQ(adam.state().m, s_before.m);
    EXPECT_EQ(adam.state().v, s_before.v);
    EXPECT_EQ(adam.state().step, 1);
    EXPECT_EQ(adam.step(p.data(), g.data(), 4, 0.1f), 0u);
    EXPECT_EQ(adam.state().step, 2);
    EXPECT_THROW(adam.step(p.data(), g.data(), 3, 0.1f), std::invalid_argument);
}

// A finite gradient whose square overflows would leave v infinite (and the parameter frozen) for
// good: refused like a NaN.
TEST(Adam, OverflowingGradientIsRefused) {
    std::vector<float> p = {1.0f, 2.0f}, g = {1e30f, 0.5f};
    Adam adam(2);
    EXPECT_EQ(adam.step(p.data(), g.data(), 2, 0.1f), 1u);
    EXPECT_EQ(p[0], 1.0f);
    EXPECT_EQ(adam.state().step, 0);
    for (float v : adam.state().v) EXPECT_TRUE(std::isfinite(v));
}

TEST(AdamState, SerialisationRoundTripIsExact) {
    std::vector<float> p = {1.0f, -2.0f, 3.0f}, g = {0.3f, 1e-4f, -7.0f};
    Adam adam(3);
    for (int i = 0; i < 5; ++i) adam.step(p.data(), g.data(), 3, 0.01f);
    const std::string blob = serialize_adam_state(adam.state());
    EXPECT_EQ(blob.size(), 28u + 8u * 3u);
    Adam resumed(3);
    resumed.set_state(deserialize_adam_state(blob));
    EXPECT_EQ(resumed.state().m, adam.state().m);
    EXPECT_EQ(resumed.state().v, adam.state().v);
    EXPECT_EQ(resumed.state().step, 5);
    std::vector<float> q = p;  // a resumed fit takes bit-identical steps
    adam.step(p.data(), g.data(), 3, 0.01f);
    resumed.step(q.data(), g.data(), 3, 0.01f);
    EXPECT_EQ(p, q);
    EXPECT_EQ(deserialize_adam_state(serialize_adam_state(AdamState{})).m.size(), 0u);
}

TEST(AdamState, RejectsTruncatedOrMismatchedBlobs) {
    Adam adam(4);
    const std::string blob = serialize_adam_state(adam.state());
    for (size_t len : {size_t(0), size_t(7), size_t(27), size_t(28), blob.size() - 1})
        EXPECT_THROW(deserialize_adam_state(blob.substr(0, len)), std::runtime_error) << len;
    EXPECT_THROW(deserialize_adam_state(blob + '\0'), std::runtime_error);
    std::string bad_magic = blob, bad_version = blob, huge_n = blob;
    bad_magic[0] = 'X';
    bad_version[8] = 2;
    huge_n[27] = char(0x40);  // top byte of n
    for (const std::string* b : {&bad_magic, &bad_version, &huge_n})
        EXPECT_THROW(deserialize_adam_state(*b), std::runtime_error);
    Adam other(5);
    EXPECT_THROW(other.set_state(deserialize_adam_state(blob)), std::runtime_error);
}

// ---- SGDR ---------------------------------------------------------------------------------

// torch.optim.lr_scheduler.CosineAnnealingWarmRestarts.step(epoch), transcribed.
double pytorch_sgdr(double base, double eta_min, int t0, int t_mult, int epoch) {
    double t_cur = epoch, t_i = t0;
    if (epoch >= t0) {
        if (t_mult == 1) {
            t_cur = epoch % t0;
        } else {
            const int n = int(std::log(double(epoch) / t0 * (t_mult - 1) + 1) / std::log(double(t_mult)));
            t_cur = epoch - t0 * (std::pow(t_mult, n) - 1) / (t_mult - 1);
            t_i = t0 * std::pow(t_mult, n);
        }
    }
    return eta_min + (base - eta_min) * (1 + std::cos(3.14159265358979323846 * t_cur / t_i)) / 2;
}

TEST(CosineWarmRestarts, CycleLandmarks) {
    const CosineWarmRestarts s(0.1f, 500, 1, 0.01f);
    EXPECT_FLOAT_EQ(s.lr_at(0), 0.1f);
    EXPECT_FLOAT_EQ(s.lr_at(250), 0.055f);
    EXPECT_FLOAT_EQ(s.lr_at(500), 0.1f);
    EXPECT_FLOAT_EQ(s.lr_at(1750), 0.055f);
    EXPECT_GT(s.lr_at(499), 0.01f);
    EXPECT_LT(s.lr_at(499), 0.0101f);
    for (int i = 1; i < 500; ++i) EXPECT_LT(s.lr_at(i), s.lr_at(i - 1)) << i;
    EXPECT_FLOAT_EQ(CosineWarmRestarts(0.2f).lr_at(250), 0.1f);  // default period 500, eta_min 0
}

TEST(CosineWarmRestarts, TMultTwoDoublesSecondPeriod) {
    const CosineWarmRestarts s(1.0f, 100, 2, 0.0f);
    for (int start : {0, 100, 300, 700}) EXPECT_FLOAT_EQ(s.lr_at(start), 1.0f) << start;
    EXPECT_FLOAT_EQ(s.lr_at(50), 0.5f);
    EXPECT_FLOAT_EQ(s.lr_at(200), 0.5f);  // halfway through the 200-long second cycle
    EXPECT_FLOAT_EQ(s.lr_at(500), 0.5f);
    EXPECT_LT(s.lr_at(299), 1e-3f);
    int64_t start, length;
    s.cycle_of(299, &start, &length);
    EXPECT_EQ(start, 100);
    EXPECT_EQ(length, 200);
}

TEST(CosineWarmRestarts, MatchesPyTorchFormula) {
    struct Case {
        int t0, t_mult;
    };
    for (Case c : {Case{500, 1}, Case{100, 2}, Case{7, 3}, Case{50, 4}})
        for (int it : {0, 1, 37, 123, 333, 499, 501, 777, 1234, 5003, 99999}) {
            const double ref = pytorch_sgdr(0.03, 0.001, c.t0, c.t_mult, it);
            EXPECT_NEAR(CosineWarmRestarts(0.03f, c.t0, c.t_mult, 0.001f).lr_at(it), ref, 1e-8)
                << c.t0 << "/" << c.t_mult << " it=" << it;
        }
}

TEST(CosineWarmRestarts, RejectsBadArguments) {
    EXPECT_THROW(CosineWarmRestarts(0.1f, 0), std::invalid_argument);
    EXPECT_THROW(CosineWarmRestarts(0.1f, 500, 0), std::invalid_argument);
    EXPECT_THROW(CosineWarmRestarts(0.1f).lr_at(-1), std::invalid_argument);
}

// ---- early stopping -----------------------------------------------------------------------

TEST(EarlyStopping, StopsAfterPatienceNonImprovingUpdates) {
    EarlyStopping es(3, 0.0f);
    EXPECT_EQ(es.best_iteration(), -1);
    EXPECT_FALSE(es.improved());
    EXPECT_FALSE(es.update(1.0, 0));
    EXPECT_FALSE(es.update(0.5, 10));
    EXPECT_TRUE(es.improved());
    EXPECT_FALSE(es.update(0.6, 20));
    EXPECT_FALSE(es.improved());
    EXPECT_FALSE(es.update(0.2, 30));  // improvement resets the count
    EXPECT_FALSE(es.update(0.3, 40));
    EXPECT_FALSE(es.update(std::numeric_limits<double>::quiet_NaN(), 50));
    EXPECT_TRUE(es.update(0.2, 60));  // equal is not better: third in a row
    EXPECT_EQ(es.best_iteration(), 30);
    EXPECT_EQ(es.best_loss(), 0.2);
    EXPECT_TRUE(es.update(0.1, 70) == false);  // a later improvement resets it
}

TEST(EarlyStopping, MinDeltaRespected) {
    EarlyStopping es(2, 0.1f);
    es.update(1.0, 0);
    EXPECT_FALSE(es.update(0.95, 1));
    EXPECT_FALSE(es.improved());
    EXPECT_EQ(es.best_loss(), 1.0);
    EXPECT_FALSE(es.update(0.85, 2));
    EXPECT_TRUE(es.improved());
    EXPECT_EQ(es.best_iteration(), 2);
    EXPECT_FALSE(es.update(0.76, 3));
    EXPECT_TRUE(es.update(0.751, 4));
    EXPECT_EQ(es.best_iteration(), 2);
    EXPECT_THROW(EarlyStopping(0, 0.0f), std::invalid_argument);
    EXPECT_THROW(EarlyStopping(5, -1.0f), std::invalid_argument);
}

}  // namespace
}  // namespace lpt
