// glTF meshes (tinygltf underneath, our checks on what it returns): text .gltf when the input
// starts with '{', binary .glb otherwise.
#include "core/mesh.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const bool text = size > 0 && data[0] == '{';
    const std::string path = lpt::fuzz::write_input(text ? "mesh.gltf" : "mesh.glb", data, size);
    LPT_FUZZ_EXPECT_CLEAN(path, lpt::load_mesh_file(path));
    return 0;
}
