// safetensors weights (vae/safetensors.cpp): header, byte ranges, dtype conversion.
#include "fuzz_util.h"
#include "vae/safetensors.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string name = "weights.safetensors";
    try {
        const lpt::SafeTensors st =
            lpt::SafeTensors::parse(std::string(reinterpret_cast<const char*>(data), size), name);
        for (const auto& [tensor, info] : st.tensors()) (void)st.to_float(tensor);
    } catch (const std::exception& e) {
        lpt::fuzz::check_rejection(e, name);
    }
    return 0;
}
