// Plugins for tests/core/test_plugin_loader.cpp, built from this one source (tests/CMakeLists.txt)
// in three modes: 0 with this build's interface fingerprint, 1 with another build's, 2 without
// the handshake. latentpt_probe_mode() says which one the loader opened.
#include "core/plugin_interface.h"
#include "latentpt_interface_fingerprint.h"

#if PROBE_MODE == 0
LPT_DEFINE_PLUGIN_INTERFACE(LPT_INTERFACE_FINGERPRINT)
#elif PROBE_MODE == 1
LPT_DEFINE_PLUGIN_INTERFACE("another build's")
#endif

extern "C" int latentpt_probe_mode() { return PROBE_MODE; }
