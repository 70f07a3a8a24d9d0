// The plugin handshake (core/plugin_interface.h): a plugin built from other headers, or one
// without the handshake, is passed over for the next place the loader searches, and refused
// with its reason when no place holds a matching one, without ever being opened. The probes
// (tests/plugin_probe) sit beside this test binary (this build's) and in its other-build/
// (another build's, none); the refused ones abort the process if their initialisers run.
#include "core/plugin_loader.h"
#include "test_util.h"
#include <cstdlib>
#include <filesystem>
#include <gtest/gtest.h>
#include <stdexcept>
#include <string>

namespace {

namespace fs = std::filesystem;

// LATENTPT_PLUGIN_DIR, searched first, points at the other build's probes.
void search_other_build_first() {
    const fs::path here = fs::read_symlink("/proc/self/exe").parent_path();
    setenv("LATENTPT_PLUGIN_DIR", (here / "other-build").c_str(), 1);
}

std::string load_failure(const std::string& file_name) {
    return lpt::test::runtime_error_of([&] { lpt::plugin_symbol(file_name, "latentpt_probe_mode"); });
}

}  // namespace

TEST(PluginLoader, PassesOverAPluginOfOtherHeadersForTheOneOfThisBuild) {
    search_other_build_first();
    using ModeFn = int (*)();
    const auto mode = reinterpret_cast<ModeFn>(lpt::plugin_symbol("liblatentpt_probe.so", "latentpt_probe_mode"));
    EXPECT_EQ(mode(), 0);  // other-build/liblatentpt_probe.so, found first, is mode 1
}

TEST(PluginLoader, RefusesAPluginBuiltFromOtherHeaders) {
    search_other_build_first();
    const std::string why = load_failure("liblatentpt_probe_foreign.so");
    EXPECT_NE(why.find("other-build/liblatentpt_probe_foreign.so: built from other headers"), std::string::npos) << why;
    EXPECT_NE(why.find("another build's"), std::string::npos) << why;
}

TEST(PluginLoader, RefusesAPluginWithoutTheHandshake) {
    search_other_build_first();
    const std::string why = load_failure("liblatentpt_probe_unmarked.so");
    EXPECT_NE(why.find("other-build/liblatentpt_probe_unmarked.so: has no interface fingerprint"), std::string::npos)
        << why;
}
