// ParamStore: maps, their derivatives (central differences), clamps and JSON round trip.
#include "latent/param_store.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace lpt;

namespace {
ParamStore make_store() {
    ParamStore ps;
    ps.add("a.La", "La", ParamMap::Identity, 4, -6.f, 6.f);
    ps.add("a.bsdf.reflectance", "reflectance", ParamMap::Sigmoid, 4, -1e9f, 1e9f);
    ps.add("a.Lc", "Lc", ParamMap::PosNeg, 4, 0.f, 1.f);
    ps.add("a.Le", "Le", ParamMap::Gain, 4, -6.f, 6.f);
    ps.init_uniform("La", -1.f, 1.f, 1);
    ps.init_uniform("reflectance", -2.f, 2.f, 2);
    ps.init_uniform("Lc", 0.f, 1.f, 3);
    ps.init_uniform("Le", -1.f, 1.f, 4);
    ps.raw()[ps.slice(3).raw_offset + 4] = 0.7f;  // a log-gain away from 0, so ∂v/∂u ≠ 1
    ps.update_values();
    return ps;
}
}  // namespace

TEST(ParamStore, BackwardMatchesFiniteDifferencesOfEveryMap) {
    ParamStore ps = make_store();
    // Loss = sum_c w_c * value_c with fixed weights: d loss / d value = w.
    std::vector<float> w(ps.values().size());
    for (size_t i = 0; i < w.size(); ++i) w[i] = 0.3f + 0.1f * float(i);
    auto loss = [&](ParamStore& p) {
        p.update_values();
        double l = 0;
        for (size_t i = 0; i < w.size(); ++i) l += double(w[i]) * p.values()[i];
        return l;
    };
    ps.zero_grad();
    ps.grad_values() = w;
    ps.backward();
    const float h = 1e-3f;
    for (size_t k = 0; k < ps.raw().size(); ++k) {
        ParamStore p = ps;
        p.raw()[k] += h;
        double lp = loss(p);
        p.raw()[k] -= 2 * h;
        double lm = loss(p);
        double fd = (lp - lm) / (2 * h);
        EXPECT_NEAR(ps.grad_raw()[k], fd, 1e-3 * std::max(1.0, std::abs(fd))) << "raw index " << k;
    }
}

TEST(ParamStore, SetValueRoundTripsThroughEveryMap) {
    ParamStore ps = make_store();
    const float v[4] = {-0.5f, 0.f, 0.25f, 0.9f};
    for (int s : {0, 2, 3}) {
        ps.set_value(s, v);
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(ps.value(s)[c], v[c], 1e-6f);
    }
    const float r[4] = {0.1f, 0.5f, 0.75f, 0.99f};
    ps.set_value(1, r);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(ps.value(1)[c], r[c], 1e-5f);
    const float bad[4] = {1.5f, 0.f, 0.f, 0.f};
    EXPECT_THROW(ps.set_value(1, bad), std::invalid_argument);  // sigmoid cannot reach 1.5
    EXPECT_THROW(ps.set_value(2, bad), std::invalid_argument);  // PosNeg parts limited to [0, 1]
    // A gain slice reaches values far outside its vector's [-6, 6]: through its log-gain alone.
    const float big[4] = {300.f, -45.f, 0.f, 2.f};
    ps.set_value(3, big);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(ps.value(3)[c], big[c], 1e-5f * 300.f);
    EXPECT_NEAR(ps.raw()[ps.slice(3).raw_offset + 4], std::log(300.f / 6.f), 1e-5f);
    const float beyond[4] = {6.f * std::exp(kGainHi + 1.f), 0.f, 0.f, 0.f};
    EXPECT_THROW(ps.set_value(3, beyond), std::invalid_argument);
    // the largest value the map makes comes back
    const float largest[4] = {6.f * std::exp(kGainHi), 0.f, 0.f, 0.f};
    ps.set_value(3, largest);
    EXPECT_FLOAT_EQ(ps.value(3)[0], largest[0]);
}

// A value refused at its last channel, or not finite, leaves every raw parameter as it was (it
// used to write the channels before the bad one: raw and values then disagreed).
TEST(ParamStore, ARefusedValueLeavesTheRawParameters) {
    ParamStore ps = make_store();
    const std::vector<float> before = ps.raw();
    const float last_bad[4] = {0.1f, 0.5f, 0.75f, 1.5f};
    for (int s : {0, 1, 2, 3}) {
        const float* bad = s == 1 ? last_bad : nullptr;
        const float nan_last[4] = {0.1f, 0.2f, 0.3f, std::nanf("")};
        EXPECT_THROW(ps.set_value(s, bad ? bad : nan_last), std::invalid_argument) << s;
        EXPECT_EQ(ps.raw(), before) << s;
    }
    const float posneg_bad[4] = {0.1f, 0.2f, 0.3f, 4.f};  // PosNeg parts limited to [0, 1]
    EXPECT_THROW(ps.set_value(2, posneg_bad), std::invalid_argument);
    EXPECT_EQ(ps.raw(), before);
}

TEST(ParamStore, GainReachesBothSignsOfAnAsymmetricRange) {
    ParamStore ps;
    ps.add("a.Le", "Le", ParamMap::Gain, 3, -2.f, 6.f);
    const float v[3] = {-40.f, 100.f, 0.f};  // -40 needs e^g >= 20, 100 only 16.7
    ps.set_value(0, v);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ps.value(0)[c], v[c], 1e-4f);
    EXPECT_NEAR(ps.raw()[3], std::log(20.f), 1e-5f);
    EXPECT_THROW(ps.add("b.Le", "Le", ParamMap::Gain, 3, 0.5f, 6.f), std::invalid_argument);  // 0 out of reach
}

TEST(ParamStore, ClampKeepsRawInRange) {
    ParamStore ps = make_store();
    for (float& r : ps.raw()) r = 100.f;
    ps.clamp_raw();
    EXPECT_FLOAT_EQ(ps.value(0)[0], 6.f);
    EXPECT_FLOAT_EQ(ps.value(2)[0], 0.f);                      // pos = neg = 1 after the clamp
    EXPECT_GT(ps.raw()[ps.slice(1).raw_offset], 99.f);         // sigmoid raw is unbounded
    EXPECT_FLOAT_EQ(ps.value(3)[0], 6.f * std::exp(kGainHi));  // vector and log-gain at their limits
}

TEST(ParamStore, GainStartsAtOneSoItsFirstValuesAreIdentitys) {
    ParamStore gain, identity;
    gain.add("a.Le", "Le", ParamMap::Gain, 16, -6.f, 6.f);
    identity.add("a.Le", "Le", ParamMap::Identity, 16, -6.f, 6.f);
    gain.init_uniform("Le", -0.1f, 0.1f, 9);
    identity.init_uniform("Le", -0.1f, 0.1f, 9);
    EXPECT_EQ(gain.values(), identity.values());
    EXPECT_EQ(gain.raw().back(), 0.f);
    gain.raw().back() = 3.f;  // a fresh initialisation starts the gain again
    gain.init_uniform("Le", -0.1f, 0.1f, 9);
    EXPECT_EQ(gain.values(), identity.values());
}

TEST(ParamStore, JsonRoundTripIsExact) {
    ParamStore a = make_store();
    ParamStore b = make_store();
    for (float& r : b.raw()) r = 0.f;
    b.load_json(a.to_json(), "params.json");
    b.update_values();
    EXPECT_EQ(a.raw(), b.raw());
    EXPECT_EQ(a.values(), b.values());
}

TEST(ParamStore, JsonErrorsNameFileAndParameter) {
    ParamStore ps = make_store();
    auto expect_error = [&](const std::string& json, const std::string& needle) {
        test::expect_error_naming([&] { ps.load_json(json, "fit/params.json"); }, {"fit/params.json", needle},
                                  "expected an error for " + json);
    };
    expect_error(R"({"slices": [{"name": "ghost.La", "raw": [0,0,0,0]}]})", "ghost.La");
    expect_error(R"({"slices": [{"name": "a.La", "raw": [0,0]}]})", "a.La");
    expect_error(R"({"slices": [{"name": "a.La", "map": "sigmoid", "raw": [0,0,0,0]}]})", "sigmoid");
    expect_error(R"({"slices": [)", "malformed");
    expect_error(R"({"slices": [{"name": "a.Le", "raw": [0,0,0,0,1e4]}]})", "log-gain");  // e^1e4 overflows
    EXPECT_THROW(ps.add("a.La", "La", ParamMap::Identity, 4, -6.f, 6.f), std::invalid_argument);
}
