// Image files: EXR written by OpenEXR, PNG by libpng, any format read through OpenImageIO (a
// plugin opened on the first read, core/image_reader.h). Writes are atomic: the data goes to a temporary file in the
// destination folder, which is renamed over the target only once complete, so an interrupted
// run never leaves a truncated image.
#pragma once
#include <string>
#include <vector>

namespace lpt {

struct Image {
    int width = 0, height = 0, channels = 0;
    std::vector<float> data;  ///< interleaved, row-major from the top-left
    std::vector<std::string> channel_names;
    /// Display values (already through a display mapping, about [0, 1]) rather than linear
    /// radiance: a reference after fit's tone, a decoded latent. write_exr records it in the
    /// header (core/image_reader.h kDisplayValuesAttribute) and read_image reads it back, so that
    /// readers which map an EXR's linear values to display ones (metrics, encode) leave these be.
    bool display = false;
    /// What the pixels were made from, as the writer's fingerprint (a cached reference's scene,
    /// defines and edit: pipeline/reference.h), kept in an EXR's header (kSourceAttribute) and
    /// read back; empty: not recorded.
    std::string source = {};
};

/// 32-bit float EXR, ZIP-compressed, no time stamp; `path` must end in .exr. Channel names
/// default to Y / R,G / R,G,B / R,G,B,A, or C00..C{n-1} beyond four channels.
void write_exr(const std::string& path, const Image& img);
/// 8-bit sRGB PNG preview of the first 3 channels: linear values × 2^exposure, clamped, sRGB OETF.
void write_png_srgb(const std::string& path, const Image& img, float exposure = 0.f);
/// 8-bit PNG of the first 3 channels taken as display values in [0, 1] (clamped, no curve):
/// for images that are already display-encoded, e.g. VAE outputs.
void write_png_display(const std::string& path, const Image& img);
/// Any format OIIO reads; throws std::runtime_error naming the file on failure.
Image read_image(const std::string& path);
/// Throws std::runtime_error naming `path`, the pixel and the channel of the first value of `img`
/// that is NaN or infinite: for commands whose answer would otherwise be NaN, or worse, "identical".
void require_finite_pixels(const Image& img, const std::string& path);
/// The whole file as bytes; throws SceneError(path, "", "cannot open file") if it cannot be read.
std::string read_file(const std::string& path);
/// The file name's extension in lower case, with its dot (".exr"; "" if none): how readers and
/// writers tell a file's kind from its name.
std::string lower_extension(const std::string& path);
/// Writes `contents` to path atomically (temp + rename); a write that does not complete (a full
/// disk) throws naming `path` and leaves `path` as it was.
void write_text_atomic(const std::string& path, const std::string& contents);
/// "<host>-<pid>": what this process's temporary files beside a shared output carry, so that no
/// two processes, on one node or on several sharing a file system, ever write one file.
std::string writer_tag();
/// Copies the file `from` to `to` atomically (temp + rename), replacing `to`.
void copy_file_atomic(const std::string& from, const std::string& to);

float linear_to_srgb(float v);

}  // namespace lpt
