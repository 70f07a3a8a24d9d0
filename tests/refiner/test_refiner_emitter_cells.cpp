// The refiner reading where emitters lie inside each latent pixel (--refiner-emitter-cells,
// docs/refiner.md "Emitter cells").
#include "refiner/refiner.h"
#include "refiner/refiner_problem.h"
#include <gtest/gtest.h>
#include <random>
#include <string>

using namespace lpt;
using namespace lpt::refiner_test;

namespace {

/// make_problem's view with 2 × 2 emitter cells of random coverage, and a target that depends on
/// where inside the pixel the coverage lies, which the latent and AOVs do not carry: target +=
/// 0.25 (left cells − right cells) on channel 3. Only a refiner that reads the cells can learn it.
Problem with_edge_residual(int w, int h, unsigned seed) {
    Problem p = make_problem(w, h);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int i = 0; i < w * h; ++i) {
        float cell[4];
        for (float& c : cell) c = u(rng);
        p.in.emitter.insert(p.in.emitter.end(), cell, cell + 4);
        p.target[size_t(i) * kC + 3] += 0.25f * (cell[0] + cell[2] - cell[1] - cell[3]);
    }
    return p;
}

}  // namespace

// Starts as the identity; a view without the cells is refused naming them; trained on four views
// that share latent and AOVs but not the cells, the refiner that reads them predicts the
// residual of a fifth where the latent-only refiner cannot beat its mean (the residual's variance
// is 4 · 0.0625 / 12 ≈ 0.021); the choice survives save/load, and a checkpoint without cells
// is refused naming --emitter-cells.
TEST(Refiner, EmitterCellsLearnWhereInsideThePixelTheEdgeLies) {
    RefinerConfig cfg = small();
    cfg.emitter_cells = 2;
    const Problem train = with_edge_residual(20, 20, 1);
    RefinerInput bare = train.in;
    bare.emitter.pop_back();
    expect_identity_and_refusal(cfg, train.in, bare, "emitter cells");

    const ExtraInputScores s = train_with_and_without(
        cfg, [](unsigned seed) { return with_edge_residual(20, 20, seed); }, 3, "--emitter-cells", "refiner_cells");
    EXPECT_GT(s.without, 0.015);
    EXPECT_LT(s.with_input, 0.3 * s.without) << "with cells " << s.with_input << ", without " << s.without;
    EXPECT_EQ(s.loaded.emitter_cells, 2);
}
