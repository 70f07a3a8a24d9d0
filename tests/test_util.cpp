#include "test_util.h"
#include "core/sampler.h"
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace lpt::test {

namespace {

/// latentpt-test-<pid> in the system's temp folder, removed at process exit.
class ProcessTempDir {
public:
    ProcessTempDir()
        : m_path(std::filesystem::temp_directory_path() / ("latentpt-test-" + std::to_string(::getpid()))) {}
    ~ProcessTempDir() {
        std::error_code ignored;
        std::filesystem::remove_all(m_path, ignored);
    }
    const std::filesystem::path& path() const { return m_path; }

private:
    std::filesystem::path m_path;
};

const std::filesystem::path& process_temp_dir() {
    static const ProcessTempDir dir;
    std::filesystem::create_directories(dir.path());
    return dir.path();
}

}  // namespace

std::string temp_dir(const std::string& name) {
    namespace fs = std::filesystem;
    const fs::path p = process_temp_dir() / name;
    fs::remove_all(p);
    fs::create_directories(p);
    return p.string();
}

std::string write_temp_file(const std::string& name, const std::string& contents) {
    namespace fs = std::filesystem;
    fs::path p = process_temp_dir() / name;
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
