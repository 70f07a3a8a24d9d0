// Shared test helpers: temp files, the ../shared data folder, statistics.
#pragma once
#include <string>

namespace lpt::test {

/// A fresh file path in a per-process temp dir; the file is written with `contents`.
std::string write_temp_file(const std::string& name, const std::string& contents);
/// ../shared (LATENTPT_SHARED env var overrides); empty string if it does not exist.
std::string shared_dir();

}  // namespace lpt::test
