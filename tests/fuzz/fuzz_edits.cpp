// edits.json (core/scene_edit.cpp) against the bundled Cornell box: ids, paths, transforms.
#include "core/scene.h"
#include "core/scene_edit.h"
#include "core/scene_loader.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const lpt::Scene scene = lpt::load_scene(lpt::fuzz::bundled_scene());
    const std::string path = lpt::fuzz::write_input("edits.json", data, size);
    LPT_FUZZ_EXPECT_CLEAN(path, lpt::load_edits(path, scene));
    return 0;
}
