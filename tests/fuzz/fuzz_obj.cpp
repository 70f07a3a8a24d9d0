// OBJ meshes (core/mesh.cpp): every option of the reader.
#include "core/mesh.h"
#include "fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string path = lpt::fuzz::write_input("mesh.obj", data, size);
    LPT_FUZZ_EXPECT_CLEAN(path, lpt::load_mesh_file(path, size % 2 == 1, size % 3 == 1));
    return 0;
}
