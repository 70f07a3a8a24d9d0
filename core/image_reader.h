// Reading image files of any format OpenImageIO knows. OpenImageIO itself lives in a plugin
// (core/plugins/oiio_image_reader.cpp, liblatentpt_oiio.so) opened on the first read, so that
// processes which only write images (a render) never pay for loading it; writing EXR and PNG
// goes through OpenEXR and libpng directly (image_io.cpp).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace lpt {

/// The EXR header attribute whose string value kDisplayValues marks the values as display values
/// (already display-mapped, about [0, 1]); files without it hold linear values.
inline constexpr const char* kDisplayValuesAttribute = "latentpt:values";
inline constexpr const char* kDisplayValues = "display";
/// The EXR header attribute that holds Image::source.
inline constexpr const char* kSourceAttribute = "latentpt:source";

/// An image file's header, as read before any pixel is decoded.
struct ImageFileInfo {
    int width = 0, height = 0, depth = 1, channels = 0;
    std::vector<std::string> channel_names;
    bool is_float = false;  ///< float, half or double samples
    bool is_uint8 = false;  ///< 8-bit samples
    /// The header marks the values as display values (kDisplayValuesAttribute).
    bool display_values = false;
    /// The header's kSourceAttribute; empty without one.
    std::string source;
};

class ImageFileReader {
public:
    virtual ~ImageFileReader() = default;
    virtual const ImageFileInfo& info() const = 0;
    /// All channels interleaved, row-major from the top-left, into `out` (width·height·channels
    /// values). Integer formats other than 8-bit come back normalised to [0, 1]. Throws
    /// std::runtime_error naming the file when the data cannot be decoded.
    virtual void read_float(float* out) = 0;
    virtual void read_uint8(uint8_t* out) = 0;
};

/// Opens `path`; with `unassociated_alpha`, colour comes back as stored rather than multiplied
/// by alpha. Throws std::runtime_error naming the file when it cannot be opened.
std::unique_ptr<ImageFileReader> open_image_file(const std::string& path, bool unassociated_alpha = false);

/// The plugin's entry point: a new reader, or null with a message in `error`.
using OpenImageFileFn = ImageFileReader* (*)(const char* path, bool unassociated_alpha, std::string* error);
inline constexpr const char* kImagePluginFile = "liblatentpt_oiio.so";
inline constexpr const char* kImagePluginSymbol = "latentpt_open_image_file";

}  // namespace lpt
