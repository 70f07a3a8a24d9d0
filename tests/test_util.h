// Shared test helpers: temp files, the ../shared data folder, statistics, error messages.
#pragma once
#include <gtest/gtest.h>
#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <utility>
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

/// The message of the `Error` `run` throws; "" when it returns normally.
template <class Error, class Run>
std::string error_of(Run&& run) {
    try {
        std::forward<Run>(run)();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

/// The message of the std::runtime_error `run` throws; "" when it returns normally.
template <class Run>
std::string runtime_error_of(Run&& run) {
    return error_of<std::runtime_error>(std::forward<Run>(run));
}

/// `run` must throw `Error` naming each of `parts` (a bad input's file and field, a bad option's
/// name); `if_accepted` says what went wrong when it returns instead.
template <class Error = std::runtime_error, class Run>
void expect_error_naming(Run&& run, std::initializer_list<std::string> parts,
                         const std::string& if_accepted = "the bad input was accepted") {
    const std::string what = error_of<Error>(std::forward<Run>(run));
    if (what.empty()) {
        ADD_FAILURE() << if_accepted;
        return;
    }
    for (const std::string& part : parts) EXPECT_NE(what.find(part), std::string::npos) << what;
}

}  // namespace lpt::test
