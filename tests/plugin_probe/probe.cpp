// Plugins for tests/core/test_plugin_loader.cpp, built from this one source (tests/CMakeLists.txt)
// in three modes: 0 with this build's interface fingerprint, 1 with another build's, 2 without
// the handshake. latentpt_probe_mode() says which one the loader opened.
#include "core/plugin_interface.h"
#include "latentpt_interface_fingerprint.h"

#include <cstdlib>

#if PROBE_MODE == 0
LPT_DEFINE_PLUGIN_INTERFACE(LPT_INTERFACE_FINGERPRINT)
#elif PROBE_MODE == 1
LPT_DEFINE_PLUGIN_INTERFACE("another build's")
#else
// The tag without a value, as in a library that holds the loader's code: not a fingerprint.
extern "C" __attribute__((used)) const char latentpt_probe_bare_tag[] = LPT_PLUGIN_INTERFACE_TAG;
#endif

// A refused plugin must never run: the loader reads the fingerprint from the file, so this
// initialiser, which ends the test process, runs only if a refused probe is opened.
#if PROBE_MODE != 0
[[maybe_unused]] static const int kNeverOpened = (std::abort(), 0);
#endif

extern "C" int latentpt_probe_mode() { return PROBE_MODE; }
