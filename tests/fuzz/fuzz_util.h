// Shared by the fuzz harnesses: a private folder for the files a reader opens, and the one rule
// every harness checks beyond the sanitizers: a rejected input is a std::exception whose message
// is one line naming a file in that folder. Anything else (another exception type, a message
// that names no file, a crash, a leak, undefined behaviour) is a finding.
#pragma once
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string>
#include <vector>

namespace lpt::fuzz {

/// A folder of this process's own, made on first use (removed at exit).
const std::string& work_dir();
/// Writes bytes to work_dir()/name and returns the path.
std::string write_input(const std::string& name, const uint8_t* data, size_t size);
std::string write_input(const std::string& name, const std::string& bytes);
/// Splits an input into up to `n` parts at "\n=====\n" (harnesses that read several files).
std::vector<std::string> split_parts(const uint8_t* data, size_t size, size_t n);
/// Replaces every "@DIR@" with work_dir() (seeds name files there without knowing the folder).
std::string with_dir(std::string text);
/// Aborts (a finding) unless the message is one non-empty line naming work_dir() or `name`.
void check_rejection(const std::exception& e, const std::string& name = "");
/// The bundled Cornell box (scenes/cornell-box/scene.json), for readers that need a scene.
std::string bundled_scene();

}  // namespace lpt::fuzz

/// Runs `body`; a std::exception is checked by check_rejection, anything else propagates.
#define LPT_FUZZ_EXPECT_CLEAN(name, body)        \
    try {                                        \
        body;                                    \
    } catch (const std::exception& e) {          \
        ::lpt::fuzz::check_rejection(e, (name)); \
    }
