// TAESD3 in libtorch against the golden latent and decoded image computed independently in
// PyTorch (../shared/models/taesd3/golden): max abs error ≤ 1e-3 (issue 5).
#include "core/image_io.h"
#include "test_util.h"
#include "vae/safetensors.h"
#include "vae/vae.h"
#include <gtest/gtest.h>
#include <cmath>
#include <iostream>

using namespace lpt;

namespace {

/// NCHW float tensor from the golden file as interleaved HWC.
std::vector<float> golden_hwc(const SafeTensors& st, const std::string& name, int& w, int& h, int& c) {
    const TensorInfo& t = st.tensors().at(name);
    c = int(t.shape[1]);
    h = int(t.shape[2]);
    w = int(t.shape[3]);
    std::vector<float> nchw = st.to_float(name), out(nchw.size());
    for (int k = 0; k < c; ++k)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) out[(size_t(y) * w + x) * c + k] = nchw[(size_t(k) * h + y) * w + x];
    return out;
}

float max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
    float m = 0;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
    return m;
}

}  // namespace

TEST(Taesd3, ReproducesGoldenLatentAndDecodedImage) {
    std::string shared = test::shared_dir();
    if (shared.empty()) GTEST_SKIP() << "../shared not found (set LATENTPT_SHARED)";
    const std::string dir = shared + "/models/taesd3";
    auto vae = load_taesd(dir);
    SafeTensors golden = SafeTensors::load(dir + "/golden/taesd3_golden_256.safetensors");
    Image input = read_image(dir + "/golden/golden_input_256.png");
    ASSERT_EQ(input.channels, 3);
    int lw, lh, lc, dw, dh, dc;
    std::vector<float> latent_ref = golden_hwc(golden, "latent", lw, lh, lc);
    std::vector<float> decoded_ref = golden_hwc(golden, "decoded", dw, dh, dc);

    std::vector<float> latent = vae->encode(input.data, input.width, input.height);
    ASSERT_EQ(latent.size(), latent_ref.size());
    EXPECT_LE(max_abs_diff(latent, latent_ref), 1e-3f);
    std::cout << "TAESD3 golden: latent max |error| " << max_abs_diff(latent, latent_ref);

    std::vector<float> decoded = vae->decode(latent_ref, lw, lh);
    ASSERT_EQ(decoded.size(), decoded_ref.size());
    EXPECT_LE(max_abs_diff(decoded, decoded_ref), 1e-3f);
    std::cout << ", decoded max |error| " << max_abs_diff(decoded, decoded_ref) << "\n";
}

TEST(Taesd3, RejectsBadSizesAndFiles) {
    std::string shared = test::shared_dir();
    if (shared.empty()) GTEST_SKIP() << "../shared not found (set LATENTPT_SHARED)";
    auto vae = load_taesd(shared + "/models/taesd3");
    test::expect_error_naming<std::invalid_argument>(
        [&] { vae->encode(std::vector<float>(12 * 16 * 3, 0.5f), 12, 16); }, {"not a multiple of 8"},
        "a 12 x 16 image was encoded");
    EXPECT_THROW(vae->decode(std::vector<float>(10), 2, 2), std::invalid_argument);
    test::expect_error_naming([&] { load_taesd(shared + "/models/taesd3", "taesd_missing"); },
                              {"taesd_missing_encoder.safetensors"});
    // TAEF1 has the same layout: it loads (a second latent space through the same code).
    EXPECT_NO_THROW(load_taesd(shared + "/models/taef1", "taef1", LatentConvention{16, 8, 0.3611f, 0.1159f}));
}
