// Images: our handling of what OpenImageIO returns (sizes, channel names and order, 8-bit vs
// float) through read_image and the bitmap texture loader. The format follows the magic bytes
// the seeds carry (EXR, PNG, Radiance HDR); anything else goes in as .png.
#include "core/image_io.h"
#include "core/texture.h"
#include "fuzz_util.h"
#include <cstring>

namespace {
const char* extension_of(const uint8_t* data, size_t size) {
    if (size >= 4 && std::memcmp(data, "\x76\x2f\x31\x01", 4) == 0) return ".exr";
    if (size >= 2 && std::memcmp(data, "#?", 2) == 0) return ".hdr";
    return ".png";
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static unsigned counter = 0;
    // A new name each time: the texture cache keys on path, size and mtime.
    const std::string path =
        lpt::fuzz::write_input("image" + std::to_string(counter++ % 64) + extension_of(data, size), data, size);
    LPT_FUZZ_EXPECT_CLEAN(path, lpt::read_image(path));
    LPT_FUZZ_EXPECT_CLEAN(path, lpt::Texture::load_bitmap(path, size % 2 == 1));
    return 0;
}
