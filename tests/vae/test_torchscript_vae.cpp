// The TorchScript VAE path (what the SD3.5 VAE uses) against the native TAESD3: the test exports
// TAESD3 with tools/export_taesd3.py (Debian's python3-torch) and requires both paths to give the
// same latents and images; a "raw"/[-1, 1] config must apply scale, shift and range maps exactly;
// bad files and configs are errors naming the file and field.
#include "test_util.h"
#include "vae/vae.h"
#include <gtest/gtest.h>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

using namespace lpt;
namespace fs = std::filesystem;

namespace {

/// A Python with torch: $LATENTPT_PYTHON, /usr/bin/python3 (Debian's python3-torch), python3.
std::string python_with_torch() {
    std::vector<std::string> candidates;
    if (const char* p = std::getenv("LATENTPT_PYTHON")) candidates.push_back(p);
    candidates.push_back("/usr/bin/python3");
    candidates.push_back("python3");
    for (const std::string& py : candidates)
        if (std::system((py + " -c 'import torch' >/dev/null 2>&1").c_str()) == 0) return py;
    return "";
}

/// Exports TAESD3 once per process; empty if Python/torch or the weights are missing.
const std::string& exported_dir() {
    static std::string dir = [] {
        const std::string shared = test::shared_dir(), py = python_with_torch();
        if (shared.empty() || py.empty()) return std::string();
        const fs::path out = test::temp_dir("torchscript-taesd3");
        const std::string cmd = py + " " LPT_SOURCE_DIR "/tools/export_taesd3.py --weights " + shared +
                                "/models/taesd3 --out " + out.string() + " >/dev/null";
        if (std::system(cmd.c_str()) != 0) return std::string("FAILED");
        return out.string();
    }();
    return dir;
}

#define REQUIRE_EXPORT(dir)                                                                                       \
    const std::string dir = exported_dir();                                                                       \
    if (dir.empty()) GTEST_SKIP() << "needs python3-torch and ../shared/models/taesd3 (scripts/install-deps.sh)"; \
    ASSERT_NE(dir, "FAILED") << "tools/export_taesd3.py failed";

std::vector<float> test_image(int w, int h) {
    std::vector<float> v(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                v[(size_t(y) * w + x) * 3 + c] =
                    0.5f + 0.45f * std::sin(0.11f * float(x * (c + 1)) + 0.07f * float(y) + float(c));
    return v;
}

float max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
    EXPECT_EQ(a.size(), b.size());
    float m = 0;
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) m = std::max(m, std::abs(a[i] - b[i]));
    return m;
}

}  // namespace

TEST(TorchScriptVae, ExportedTaesd3MatchesNative) {
    REQUIRE_EXPORT(dir);
    auto native = load_taesd(test::shared_dir() + "/models/taesd3");
    auto ts = load_torchscript_vae(dir + "/encoder.pt", dir + "/decoder.pt", dir + "/vae.json");
    EXPECT_EQ(ts->convention().channels, 16);
    const int w = 48, h = 32;  // not square, not the size of any trace
    const std::vector<float> img = test_image(w, h);
    const std::vector<float> za = native->encode(img, w, h), zb = ts->encode(img, w, h);
    EXPECT_LT(max_abs_diff(za, zb), 1e-4f);
    EXPECT_LT(max_abs_diff(native->decode(za, w / 8, h / 8), ts->decode(za, w / 8, h / 8)), 1e-4f);
}

TEST(TorchScriptVae, RawLatentsAndSignedRangeAreMappedBack) {
    REQUIRE_EXPORT(dir);
    // The same modules described as a "raw"/[-1, 1] VAE: latentpt must hand the modules
    // 2x-1 and (z/scale + shift), and undo both, so the composition differs from the model-space
    // description by exactly those affine maps.
    const std::string cfg = dir + "/raw.json";
    std::ofstream(cfg)
        << R"({"channels": 16, "downsample": 8, "scale": 2.0, "shift": 0.5, "image_range": [-1, 1], "latent": "raw"})";
    auto model = load_torchscript_vae(dir + "/encoder.pt", dir + "/decoder.pt", dir + "/vae.json");
    auto raw = load_torchscript_vae(dir + "/encoder.pt", dir + "/decoder.pt", cfg);
    const int w = 16, h = 16;
    std::vector<float> img = test_image(w, h), img_m(img.size());
    for (size_t i = 0; i < img.size(); ++i) img_m[i] = 2.f * img[i] - 1.f;  // what "raw" feeds the encoder
    const std::vector<float> zm = model->encode(img_m, w, h), zr = raw->encode(img, w, h);
    std::vector<float> expect(zm.size());
    for (size_t i = 0; i < zm.size(); ++i) expect[i] = (zm[i] - 0.5f) * 2.f;
    EXPECT_LT(max_abs_diff(zr, expect), 1e-5f);
    const std::vector<float> xr = raw->decode(zr, w / 8, h / 8);
    std::vector<float> zback(zr.size());
    for (size_t i = 0; i < zr.size(); ++i) zback[i] = zr[i] / 2.f + 0.5f;
    std::vector<float> xm = model->decode(zback, w / 8, h / 8);
    for (float& v : xm) v = (v + 1.f) / 2.f;
    EXPECT_LT(max_abs_diff(xr, xm), 1e-5f);
}

TEST(TorchScriptVae, BadFilesAndConfigsNameTheProblem) {
    const fs::path d = test::temp_dir("torchscript-bad");
    auto expect_error = [](const std::string& enc, const std::string& dec, const std::string& cfg,
                           const std::string& needle) {
        test::expect_error_naming([&] { load_torchscript_vae(enc, dec, cfg); }, {needle},
                                  "accepted; expected an error with '" + needle + "'");
    };
    const std::string cfg = (d / "vae.json").string(), junk = (d / "junk.pt").string();
    std::ofstream(junk) << "not a module";
    expect_error("e.pt", "d.pt", (d / "none.json").string(), "none.json");
    std::ofstream(cfg) << R"({"channels": 16, "downsample": 8, "scale": 1.5, "shift": 0.1, "image_range": [0, 1]})";
    expect_error("e.pt", "d.pt", cfg, "'latent'");
    std::ofstream(cfg)
        << R"({"channels": 16, "downsample": 8, "scale": 1.5, "shift": 0.1, "image_range": [0, 1], "latent": "weird"})";
    expect_error("e.pt", "d.pt", cfg, "latent");
    std::ofstream(cfg) << R"({"channels": 16, "downsample": 8, "scale": 1.5, "shift": 0.1, "image_range": [0, 1],
                             "latent": "raw", "scaling_factor": 1.5})";
    expect_error("e.pt", "d.pt", cfg, "field 'scaling_factor': unknown key");
    std::ofstream(cfg)
        << R"({"channels": 16, "downsample": 8, "scale": 1.5, "shift": 0.1, "image_range": [0, 1], "latent": "raw"})";
    expect_error((d / "missing.pt").string(), junk, cfg, "missing.pt");
    expect_error(junk, junk, cfg, "junk.pt");
    std::ofstream(cfg) << "{ broken";
    expect_error(junk, junk, cfg, "vae.json");
}
