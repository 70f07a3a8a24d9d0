#include "test_util.h"
#include "core/sampler.h"
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace lpt::test {

std::string write_temp_file(const std::string& name, const std::string& contents) {
    namespace fs = std::filesystem;
    fs::path dir = fs::temp_directory_path() / ("latentpt-test-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    fs::path p = dir / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << contents;
    return p.string();
}

std::string shared_dir() {
    namespace fs = std::filesystem;
    if (const char* env = std::getenv("LATENTPT_SHARED")) {
        if (fs::is_directory(env)) return env;
    }
    return fs::is_directory(LPT_SHARED_DIR) ? std::string(LPT_SHARED_DIR) : std::string();
}

std::vector<float> random_weights(size_t n, uint64_t seed) {
    std::vector<float> w(n);
    for (size_t i = 0; i < n; ++i) w[i] = 2.f * sample_1d(seed, uint32_t(i), 0, 0) - 1.f;
    return w;
}

}  // namespace lpt::test
