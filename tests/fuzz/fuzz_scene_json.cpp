// JSON scenes (core/loaders): the whole reader, including meshes and textures it opens from the
// fuzz folder (seeds name them as @DIR@/...).
#include "core/scene_loader.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text = lpt::fuzz::with_dir(std::string(reinterpret_cast<const char*>(data), size));
    const std::string path = lpt::fuzz::write_input("scene.json", text);
    LPT_FUZZ_EXPECT_CLEAN(path, lpt::load_scene_json(path));
    return 0;
}
