// Libraries opened on demand. A command that renders a scene without textures never loads
// OpenImageIO (~0.25 s of dynamic linking) and one that needs no network never loads libtorch
// (~0.5 s): each sits in a plugin (liblatentpt_oiio.so, liblatentpt_torch.so) found here.
#pragma once
#include <string>

namespace lpt {

/// The address of `symbol` in the plugin `file_name`, opened (once per process) from the first of:
/// $LATENTPT_PLUGIN_DIR; the folder of the binary holding this code and its ../lib/latentpt;
/// the build tree's lib/; the install prefix's lib/latentpt. A plugin built from other headers or
/// with another toolchain (plugin_interface.h) is passed over for the next place. Throws
/// std::runtime_error listing every place tried and why each failed.
void* plugin_symbol(const std::string& file_name, const std::string& symbol);

}  // namespace lpt
