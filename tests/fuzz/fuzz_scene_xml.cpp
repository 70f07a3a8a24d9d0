// Mitsuba 3 XML scenes, with `$name` defaults and -D overrides (spp, res, integrator depth as the
// paper's scenes use them), plus the meshes and textures they open from the fuzz folder.
#include "core/scene_loader.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text = lpt::fuzz::with_dir(std::string(reinterpret_cast<const char*>(data), size));
    const std::string path = lpt::fuzz::write_input("scene.xml", text);
    const std::map<std::string, std::string> defines{{"spp", "4"}, {"resx", "16"}, {"resy", "12"}, {"max_depth", "5"}};
    LPT_FUZZ_EXPECT_CLEAN(path, lpt::load_scene_mitsuba_xml(path, defines));
    return 0;
}
