// Image files: multi-channel latent EXRs round-trip in channel order (EXR sorts channels by
// name), also when another tool named them C0..C15 without padding; writes are atomic; the mark
// of display values and the writer's source round-trip.
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

// An EXR of display values (a reference after fit's tone, a decoded latent) says so in its header
// and reads back marked; one of linear values reads back unmarked, with the same pixels.
TEST(ImageIo, DisplayValuesMarkRoundTrips) {
    const std::string dir = std::filesystem::path(test::write_temp_file("io-display", "")).parent_path().string();
    Image img{2, 2, 3, {0.f, 0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f, 0.7f, 0.8f, 0.9f, 1.f, 1.1f}, {"R", "G", "B"}};
    for (bool display : {true, false}) {
        img.display = display;
        const std::string path = dir + (display ? "/display.exr" : "/linear.exr");
        write_exr(path, img);
        const Image back = read_image(path);
        EXPECT_EQ(back.display, display);
        EXPECT_EQ(back.data, img.data);
    }
    img.source = "fnv1a64:0123456789abcdef";  // a writer's fingerprint (pipeline/reference.h)
    write_exr(dir + "/source.exr", img);
    EXPECT_EQ(read_image(dir + "/source.exr").source, img.source);
    EXPECT_EQ(read_image(dir + "/linear.exr").source, "");
}

// A text write that cannot complete (the disk full when the stream is flushed, here /dev/full
// standing in for the temporary file) throws naming the file and leaves the old file whole: a
// .done cut short must never be renamed into place.
TEST(ImageIo, ATextWriteThatCannotCompleteLeavesTheOldFile) {
    namespace fs = std::filesystem;
    if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
    const std::string path = test::write_temp_file("io-full/frame.done", "key old\nrow\n");
    const fs::path tmp = fs::path(path).parent_path() / (".frame.tmp" + writer_tag() + ".done");
    fs::remove(tmp);
    fs::create_symlink("/dev/full", tmp);
    test::expect_error_naming<std::runtime_error>([&] { write_text_atomic(path, "key new\nrow\n"); },
                                                  {path, "did not complete"}, "a write to a full disk succeeded");
    EXPECT_EQ(read_file(path), "key old\nrow\n");
    EXPECT_FALSE(fs::is_symlink(tmp)) << "the temporary is removed";
}

namespace {

uint32_t crc32(const std::string& bytes) {
    uint32_t c = 0xffffffffu;
    for (unsigned char b : bytes) {
        c ^= b;
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
    }
    return ~c;
}

std::string be32(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }

std::string png_chunk(const std::string& type, const std::string& data) {
    return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
}

}  // namespace

// A header that claims 200000 x 200000 pixels in a 60-byte file: refused with the size it would
// need before anything is allocated (it used to end in std::bad_alloc).
TEST(ImageIo, HugeHeaderIsRefusedBeforeAllocating) {
    const std::string ihdr = be32(200000) + be32(200000) + std::string("\x08\x02\x00\x00\x00", 5);  // 8-bit RGB
    const std::string png =
        std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", "") + png_chunk("IEND", "");
    const std::string path = test::write_temp_file("huge.png", png);
    test::expect_error_naming([&] { read_image(path); }, {"huge.png", "GiB"},
                              "a 200000 x 200000 header must be refused");
}
