// vae.json, the conventions of a TorchScript VAE (vae/vae_config.cpp).
#include "fuzz_util.h"
#include "vae/vae_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string name = "vae.json";
    LPT_FUZZ_EXPECT_CLEAN(name, lpt::parse_vae_config(std::string(reinterpret_cast<const char*>(data), size), name));
    return 0;
}
