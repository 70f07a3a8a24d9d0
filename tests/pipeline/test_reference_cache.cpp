// The reference cache's linear values (fit --exposures, docs/fitting.md "Exposure cycle"): kept
// only where asked for, traced again for a cache that lacks them with the same pixels, and
// refused where they do not map to the cached display values.
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "pipeline/reference.h"
#include "test_util.h"
#include "vae/vae.h"
#include <gtest/gtest.h>
#include <filesystem>

using namespace lpt;
using namespace lpt::pipeline;
namespace fs = std::filesystem;

namespace {

/// A stand-in VAE: each latent pixel holds its 8 × 8 block's mean of R, G, B in channels 0–2.
class BlockMeanVae : public Vae {
public:
    std::vector<float> encode(const std::vector<float>& rgb, int width, int height) const override {
        const int w = width / 8, h = height / 8, n = m_convention.channels;
        std::vector<float> latent(size_t(w) * h * n, 0.f);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    latent[(size_t(y / 8) * w + x / 8) * n + c] += rgb[(size_t(y) * width + x) * 3 + c] / 64.f;
        return latent;
    }
    std::vector<float> decode(const std::vector<float>&, int, int) const override { return {}; }
    const LatentConvention& convention() const override { return m_convention; }

private:
    LatentConvention m_convention;
};

constexpr int kSize = 16;

Scene box() {
    return load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json", {{"integrator.max_depth", "3"}});
}

struct Cached {
    std::vector<float> latent, display, linear;
};

Cached cached(const Scene& scene, const std::string& stem, bool want_linear) {
    Cached c;
    c.latent =
        cached_encoded_reference(scene, kSize, kSize, 4, kReferenceSeed, "clip", BlockMeanVae(), stem, "source A",
                                 "block means", "", c.display, {}, want_linear ? &c.linear : nullptr);
    return c;
}

}  // namespace

TEST(ReferenceCache, LinearValuesKeptWhereAskedForAndTracedAgainWithTheSamePixels) {
    const Scene scene = box();
    const std::string dir = test::temp_dir("reference-cache");
    const std::string plain = dir + "/plain", stem = dir + "/training";
    cached(scene, plain, false);
    EXPECT_TRUE(fs::exists(plain + ".exr"));
    EXPECT_FALSE(fs::exists(plain + "_linear.exr")) << "an edited frame's reference needs no linear copy";

    const Cached traced = cached(scene, stem, true);
    ASSERT_TRUE(fs::exists(stem + "_linear.exr"));
    ASSERT_EQ(traced.linear.size(), traced.display.size());
    float brightest = 0.f;
    for (size_t i = 0; i < traced.linear.size(); ++i) {
        EXPECT_EQ(traced.display[i], display_value(traced.linear[i], "clip")) << "value " << i;
        brightest = std::max(brightest, traced.linear[i]);
    }
    EXPECT_GT(brightest, 1.f) << "nothing clipped: the linear values would hold nothing the display values lack";

    EXPECT_EQ(cached(scene, stem, true).linear, traced.linear) << "read back from the cache";
    // a cache from before the linear file: the same seed traces the same pixels again
    fs::remove(stem + "_linear.exr");
    const Cached again = cached(scene, stem, true);
    EXPECT_EQ(again.linear, traced.linear);
    EXPECT_EQ(again.latent, traced.latent);
    EXPECT_TRUE(fs::exists(stem + "_linear.exr"));
}

TEST(ReferenceCache, LinearValuesThatDoNotGiveTheDisplayValuesAreRefused) {
    const Scene scene = box();
    const std::string stem = test::temp_dir("reference-cache-mismatch") + "/training";
    Cached traced = cached(scene, stem, true);
    for (float& v : traced.linear) v *= 0.5f;  // another build's, say
    write_exr(stem + "_linear.exr", Image{kSize, kSize, 3, traced.linear, {"R", "G", "B"}, false, "source A"});
    test::expect_error_naming([&] { cached(scene, stem, true); }, {stem + "_linear.exr", stem + ".exr"});
}

TEST(ReferenceCache, ALinearFileThatCannotBeReadOrWrittenIsTracedAround) {
    const Scene scene = box();
    const std::string stem = test::temp_dir("reference-cache-unwritable") + "/training";
    const Cached traced = cached(scene, stem, true);
    // a folder where the file should be: unreadable as an image, and no file can replace it (not
    // even for root, whom a read-only folder does not stop)
    fs::remove(stem + "_linear.exr");
    fs::create_directory(stem + "_linear.exr");
    Cached again;
    EXPECT_NO_THROW(again = cached(scene, stem, true));
    EXPECT_EQ(again.linear, traced.linear);
    EXPECT_TRUE(fs::is_directory(stem + "_linear.exr"));
}
