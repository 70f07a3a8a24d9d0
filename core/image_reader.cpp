#include "core/image_reader.h"
#include "core/plugin_loader.h"
#include <stdexcept>

namespace lpt {

std::unique_ptr<ImageFileReader> open_image_file(const std::string& path, bool unassociated_alpha) {
    OpenImageFileFn open = nullptr;
    try {
        open = reinterpret_cast<OpenImageFileFn>(plugin_symbol(kImagePluginFile, kImagePluginSymbol));
    } catch (const std::runtime_error& e) {
        throw std::runtime_error(path + ": cannot read images: " + e.what());
    }
    std::string error;
    std::unique_ptr<ImageFileReader> reader(open(path.c_str(), unassociated_alpha, &error));
    if (!reader) throw std::runtime_error(path + ": cannot read image: " + error);
    return reader;
}

}  // namespace lpt
