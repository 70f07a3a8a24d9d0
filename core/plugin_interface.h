// The handshake between a binary and the plugins it opens (plugin_loader.h). A plugin shares the
// binary's types: liblatentpt_torch.so takes RefineJob, Scene, ... from the executable and calls
// its functions. One built from other headers (a binary copied out of build/, then the tree
// rebuilt) would load and run with other struct layouts, or fail on a missing symbol. So both
// sides carry LPT_INTERFACE_FINGERPRINT, a hash of every header of the project and of the
// compiler and the options that change layouts or the runtime (sanitizers), made at build
// time (cmake/interface_fingerprint.cmake, the generated latentpt_interface_fingerprint.h): the
// plugin as a tagged string in its file, which the loader reads before it opens the library, so
// a plugin of another build never runs any of its code (not even its static initialisers).
#pragma once

/// What precedes the fingerprint in the plugin's file; a ';' follows it.
#define LPT_PLUGIN_INTERFACE_TAG "latentpt-plugin-interface:"

/// The plugin's side of the handshake, once per plugin, outside any namespace; `fingerprint` is
/// LPT_INTERFACE_FINGERPRINT (from latentpt_interface_fingerprint.h) in a real plugin. Exported,
/// so the linker keeps it.
#define LPT_DEFINE_PLUGIN_INTERFACE(fingerprint) \
    extern "C" __attribute__((used)) const char latentpt_plugin_interface[] = LPT_PLUGIN_INTERFACE_TAG fingerprint ";";
