// Shared by the refiner tests: a toy view whose target the refiner can learn from its AOVs, and
// small networks and trainings that run in milliseconds.
#pragma once
#include "refiner/refiner.h"
#include "test_util.h"
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace lpt::refiner_test {

constexpr int kC = 16;

/// A view whose "true" latent differs from the rendered one by a function of the AOVs, which
/// the refiner can learn: target = latent + 0.4 n_x on channel 0 − 0.3 distance on channel 5.
struct Problem {
    RefinerInput in;
    std::vector<float> target;
};

inline Problem make_problem(int w, int h) {
    Problem p;
    p.in.width = w;
    p.in.height = h;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const float nx = std::cos(0.3f * x), ny = std::sin(0.3f * x), d = 1.f + 0.05f * float(y);
            p.in.normal.insert(p.in.normal.end(), {nx, ny, 0.f});
            p.in.distance.push_back(d);
            for (int c = 0; c < kC; ++c) {
                const float l = 0.8f * std::sin(0.2f * float(x + 3 * c)) + 0.1f * u(rng);
                p.in.latent.push_back(l);
                p.target.push_back(l + (c == 0 ? 0.4f * nx : 0.f) + (c == 5 ? -0.3f * d : 0.f));
            }
        }
    return p;
}

inline double mse(const std::vector<float>& a, const std::vector<float>& b) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i) s += double(a[i] - b[i]) * (a[i] - b[i]);
    return s / double(a.size());
}

inline RefinerConfig small() {
    RefinerConfig c;
    c.expansion = 2;
    c.dropout = 0.f;
    return c;
}

inline std::string temp_path(const std::string& name) { return test::write_temp_file(name, ""); }

/// Latent losses only (no decoder), a fast learning rate, no early stopping.
inline RefinerTrainOptions latent_training(int iterations, int crop) {
    RefinerTrainOptions o;
    o.iterations = iterations;
    o.lr = 3e-3f;
    o.crop = crop;
    o.w_ssim = 1.f;  // latent MSE + D-SSIM: both latent terms exercised, no decoder
    o.w_lpips = 0.f;
    o.patience = 0;
    return o;
}

}  // namespace lpt::refiner_test
