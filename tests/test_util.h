// Shared test helpers: temp files, the ../shared data folder, statistics.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace lpt::test {

/// A fresh file path in a per-process temp dir; the file is written with `contents`.
std::string write_temp_file(const std::string& name, const std::string& contents);
/// A fresh, empty folder `name` in the per-process temp dir. The whole per-process dir is removed
/// when the test process exits, so a test run leaves nothing behind.
std::string temp_dir(const std::string& name);
/// ../shared (LATENTPT_SHARED env var overrides); empty string if it does not exist.
std::string shared_dir();
/// n deterministic weights uniform in [-1, 1): a loss Σ W · Ĩ whose gradient d_image is W.
std::vector<float> random_weights(size_t n, uint64_t seed);

}  // namespace lpt::test
