// Image files: multi-channel latent EXRs round-trip in channel order (EXR sorts channels by
// name), also when another tool named them C0..C15 without padding; writes are atomic.
#include "core/image_io.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <filesystem>

using namespace lpt;

TEST(ImageIo, SixteenChannelExrKeepsChannelOrder) {
    const std::string dir = std::filesystem::path(test::write_temp_file("io-marker", "")).parent_path().string();
    Image img{3, 2, 16, std::vector<float>(3 * 2 * 16), {}};
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = float(i % 16) + 0.01f * float(i / 16);
    write_exr(dir + "/padded.exr", img);
    Image back = read_image(dir + "/padded.exr");
    EXPECT_EQ(back.data, img.data);
    // Unpadded names as other tools write them.
    for (int c = 0; c < 16; ++c) img.channel_names.push_back("C" + std::to_string(c));
    write_exr(dir + "/unpadded.exr", img);
    back = read_image(dir + "/unpadded.exr");
    EXPECT_EQ(back.data, img.data);
    EXPECT_EQ(back.channel_names[10], "C10");
    // No temp files left behind by the atomic writes.
    for (const auto& e : std::filesystem::directory_iterator(dir))
        EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}
