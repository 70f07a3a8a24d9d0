// The handshake between a binary and the plugins it opens (plugin_loader.h). A plugin shares the
// binary's types: liblatentpt_torch.so takes RefineJob, Scene, ... from the executable and calls
// its functions. One built from other headers (a binary copied out of build/, then the tree
// rebuilt) would load and run with other struct layouts, so both sides carry
// LPT_INTERFACE_FINGERPRINT, a hash of every header of the project made at build time
// (cmake/interface_fingerprint.cmake, the generated latentpt_interface_fingerprint.h), and the
// loader passes over a plugin whose value differs from its own.
#pragma once

namespace lpt {

/// The symbol every plugin exports: `const char* latentpt_plugin_interface()`.
inline constexpr const char* kPluginInterfaceSymbol = "latentpt_plugin_interface";

}  // namespace lpt

/// The plugin's side of the handshake, once per plugin, outside any namespace; `fingerprint` is
/// LPT_INTERFACE_FINGERPRINT (from latentpt_interface_fingerprint.h) in a real plugin.
#define LPT_DEFINE_PLUGIN_INTERFACE(fingerprint) \
    extern "C" const char* latentpt_plugin_interface() { return fingerprint; }
