// Validation against a renderer nobody here wrote: Bitterli's Cornell box rendered by Tungsten
// (../shared/scenes/cornell-box/TungstenRender.exr, 1024^2). We render at 256^2 with a box
// filter and compare with the reference box-averaged 4x4, i.e. the same pixel integrals.
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "integrators/path.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>

using namespace lpt;

namespace {

std::vector<float> downsample(const Image& img, int f) {
    int w = img.width / f, h = img.height / f;
    std::vector<float> out(size_t(w) * h * 3, 0.f);
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            for (int c = 0; c < 3; ++c)
                out[((y / f) * w + x / f) * 3 + c] +=
                    img.data[(size_t(y) * img.width + x) * img.channels + c] / float(f * f);
    return out;
}

double relative_mse(const std::vector<float>& a, const std::vector<float>& ref) {
    double s = 0;
    for (size_t i = 0; i < a.size(); ++i)
        s += double(a[i] - ref[i]) * (a[i] - ref[i]) / (double(ref[i]) * ref[i] + 1e-2);
    return s / a.size();
}

}  // namespace

TEST(Tungsten, CornellBoxConvergesToIndependentReference) {
    std::string shared = test::shared_dir();
    if (shared.empty()) GTEST_SKIP() << "../shared not found (set LATENTPT_SHARED): skipping the Tungsten validation";
    const int res = 256;
    Scene scene = load_scene(shared + "/scenes/cornell-box/scene_v3.xml",
                             {{"resx", std::to_string(res)}, {"resy", std::to_string(res)}});
    scene.camera.filter = {PixelFilter::Type::Box, 0.5f};
    Image ref_full = read_image(shared + "/scenes/cornell-box/TungstenRender.exr");
    ASSERT_EQ(ref_full.width, 1024);
    std::vector<float> ref = downsample(ref_full, ref_full.width / res);
    auto spectra = SceneSpectra<3>::from_description(scene);

    std::vector<double> errors;
    std::vector<float> img;
    for (int spp : {4, 16, 64, 256}) {
        RenderOptions opt = RenderOptions::from_scene(scene);
        opt.spp = spp;
        opt.seed = 1;
        img = render_path<3>(scene, spectra, opt).develop();
        errors.push_back(relative_mse(img, ref));
        std::cout << "tungsten cornell-box " << res << "^2, " << spp << " spp: relMSE " << errors.back() << "\n";
    }
    // Monte Carlo error falls ~4x per 4x spp until it meets the floor set by the reference's own
    // noise and filtering differences; it must fall clearly at every step.
    for (size_t i = 1; i < errors.size(); ++i) EXPECT_LT(errors[i], 0.8 * errors[i - 1]) << "step " << i;
    EXPECT_LT(errors.back(), errors.front() / 10);
    for (int c = 0; c < 3; ++c) {
        double a = 0, b = 0;
        for (size_t i = c; i < img.size(); i += 3) a += img[i], b += ref[i];
        std::cout << "channel " << c << " mean ratio " << a / b << "\n";
        EXPECT_NEAR(a / b, 1.0, 0.01) << "channel " << c << ": bias against Tungsten";
    }
}
