// The refiner's U-Net body (--refiner-arch unet, docs/refiner.md "U-Net").
#include "refiner/refiner.h"
#include "refiner/refiner_problem.h"
#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

using namespace lpt;
using namespace lpt::refiner_test;

namespace {

/// Chebyshev distance from (cx, cy) of the furthest pixel whose refined latent changes when
/// pixel (cx, cy)'s input latent is nudged: how far the network sees.
int reach_of_one_pixel(const Refiner& r, const RefinerInput& in, int cx, int cy) {
    RefinerInput nudged = in;
    for (int c = 0; c < kC; ++c) nudged.latent[(size_t(cy) * size_t(in.width) + size_t(cx)) * kC + size_t(c)] += 0.5f;
    const std::vector<float> a = r.refine(in), b = r.refine(nudged);
    int reach = -1;
    for (int y = 0; y < in.height; ++y)
        for (int x = 0; x < in.width; ++x)
            for (int c = 0; c < kC; ++c) {
                const size_t i = (size_t(y) * size_t(in.width) + size_t(x)) * kC + size_t(c);
                if (std::abs(a[i] - b[i]) > 1e-6f)
                    reach = std::max(reach, std::max(std::abs(x - cx), std::abs(y - cy)));
            }
    return reach;
}

}  // namespace

// The U-Net body: the identity before training
// at sizes that are not multiples of its 4× pooling, training lowers the loss on crops of such
// sizes too, and a pixel's input reaches further than the conv body's 9×9 window (without
// InstanceNorm, whose statistics would spread it over the whole view). The choice survives
// save/load, and a checkpoint of the other body is refused naming the option.
TEST(Refiner, UNetStartsAsIdentityTrainsAndSeesFurther) {
    RefinerConfig cfg = small();
    cfg.arch = RefinerArch::UNet;
    const Problem odd = make_problem(13, 7);
    EXPECT_EQ(Refiner::create(cfg, 2)->refine(odd.in), odd.in.latent);

    const Problem p = make_problem(24, 20);
    auto unet = Refiner::create(cfg, 4);
    const double before = mse(unet->refine(p.in), p.target);
    const RefinerTrainResult res = unet->train(p.in, p.target, nullptr, nullptr, nullptr, latent_training(80, 10));
    EXPECT_EQ(res.history.size(), 80u);
    EXPECT_LT(mse(unet->refine(p.in), p.target), 0.5 * before);

    RefinerConfig plain_conv = small(), plain_unet = cfg;
    plain_conv.instance_norm = plain_unet.instance_norm = false;
    auto conv = Refiner::create(plain_conv, 4), wide = Refiner::create(plain_unet, 4);
    const Problem big = make_problem(32, 32);
    conv->train(big.in, big.target, nullptr, nullptr, nullptr, latent_training(20, 16));
    wide->train(big.in, big.target, nullptr, nullptr, nullptr, latent_training(20, 16));
    EXPECT_EQ(reach_of_one_pixel(*conv, big.in, 16, 15), 4);  // 1 + 2 + 1: the 3×3, 5×5, 3×3 blocks
    EXPECT_GE(reach_of_one_pixel(*wide, big.in, 16, 15), 10);
    EXPECT_LT(wide->parameter_count(), conv->parameter_count());

    const std::string file = temp_path("unet_refiner.pt");
    unet->save(file);
    auto loaded = Refiner::load(file);
    EXPECT_EQ(loaded->config().arch, RefinerArch::UNet);
    EXPECT_EQ(loaded->refine(p.in), unet->refine(p.in));

    const std::string ck = temp_path("unet_ck.pt");
    std::filesystem::remove(ck);
    RefinerTrainOptions o = latent_training(2, 10);
    o.checkpoint_path = ck;
    Refiner::create(cfg, 4)->train(p.in, p.target, nullptr, nullptr, nullptr, o);
    o.iterations = 4;
    o.resume = true;
    test::expect_error_naming([&] { Refiner::create(small(), 4)->train(p.in, p.target, nullptr, nullptr, nullptr, o); },
                              {"--arch unet"}, "a U-Net checkpoint resumed into the conv body");
    EXPECT_THROW(parse_refiner_arch("mlp", "--refiner-arch"), std::invalid_argument);
}
