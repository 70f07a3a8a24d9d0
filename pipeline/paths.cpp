#include "pipeline/paths.h"
#include <cstdlib>

#ifndef LPT_SOURCE_DIR
#define LPT_SOURCE_DIR "."
#endif

namespace lpt::pipeline {

std::string shared_dir() {
    const char* env = std::getenv("LATENTPT_SHARED");
    return env ? std::string(env) : std::string(LPT_SOURCE_DIR) + "/../shared";
}

std::string default_vae_dir(const std::string& dir) { return dir.empty() ? shared_dir() + "/models/taesd3" : dir; }

std::string default_lpips_dir(const std::string& dir) { return dir.empty() ? shared_dir() + "/models/lpips" : dir; }

}  // namespace lpt::pipeline
