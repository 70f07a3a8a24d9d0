#include "core/image_io.h"
#include "core/temp_file.h"
#include "core/error.h"
#include "core/film.h"
#include "core/image_reader.h"
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <png.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

namespace lpt {

namespace fs = std::filesystem;

std::string writer_tag() {
    char host[256] = {};
    if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
    return std::string(host) + "-" + std::to_string(::getpid());
}

namespace {
std::string temp_path_for(const std::string& path) {
    fs::path p(path);
    return (p.parent_path() / ("." + p.stem().string() + ".tmp" + writer_tag() + p.extension().string())).string();
}

/// Runs `write(tmp)` on a temporary file beside `path` and renames it over `path` once complete;
/// a failure removes the temporary and names `path` and `what` it is.
template <typename Write>
void write_atomically(const std::string& path, Write write, const char* what = "image") {
    const std::string tmp = temp_path_for(path);
    const TemporaryFile removed_if_interrupted(tmp);
    try {
        if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
        write(tmp);
        fs::rename(tmp, path);  // fails onto a folder of that name: the temporary must not stay
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw std::runtime_error(path + ": cannot write " + what + ": " + e.what());
    }
}

/// The names OpenImageIO gave channels when it wrote our EXRs (kept, so files stay the same):
/// Y; R,G; R,G,B; R,G,B,A; beyond four C00..C{n-1}, zero-padded because EXR stores channels
/// sorted by name and C10 would come before C2.
std::vector<std::string> exr_channel_names(const Image& img) {
    if (!img.channel_names.empty()) return img.channel_names;
    if (img.channels == 1) return {"Y"};
    std::vector<std::string> names;
    for (int c = 0; c < img.channels; ++c)
        names.push_back(img.channels <= 4 ? std::string(1, "RGBA"[c]) : (c < 10 ? "C0" : "C") + std::to_string(c));
    return names;
}

/// EXR keeps channels in name order, so latent channels "C0".."C15" written by other tools come
/// back as C0, C1, C10, ..., C15, C2, ...: put channels named C<number> in numeric order.
void reorder_numbered_channels(Image& img) {
    std::vector<std::pair<long, int>> order;
    for (int c = 0; c < img.channels; ++c) {
        const std::string& n = img.channel_names[c];
        if (n.size() < 2 || n[0] != 'C' || n.find_first_not_of("0123456789", 1) != std::string::npos) return;
        order.emplace_back(std::stol(n.substr(1)), c);
    }
    std::stable_sort(order.begin(), order.end());
    std::vector<float> data(img.data.size());
    std::vector<std::string> names(img.channels);
    for (int c = 0; c < img.channels; ++c) {
        names[c] = img.channel_names[order[c].second];
        for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
            data[i * img.channels + c] = img.data[i * img.channels + order[c].second];
    }
    img.data = std::move(data);
    img.channel_names = std::move(names);
}
}  // namespace

std::string lower_extension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

float linear_to_srgb(float v) {
    v = std::clamp(v, 0.f, 1.f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

void write_exr(const std::string& path, const Image& img) {
    if (lower_extension(path) != ".exr")
        throw std::invalid_argument(path + ": an OpenEXR file is written here; its name must end in .exr");
    const std::vector<std::string> names = exr_channel_names(img);
    if (int(names.size()) != img.channels || img.data.size() != size_t(img.width) * img.height * img.channels)
        throw std::invalid_argument(path + ": image data does not match its size and channels");
    // No write time in the header: the same pixels give the same file, so split jobs merge into
    // exactly the files of one job.
    Imf::Header header(img.width, img.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    if (img.display) header.insert(kDisplayValuesAttribute, Imf::StringAttribute(kDisplayValues));
    if (!img.source.empty()) header.insert(kSourceAttribute, Imf::StringAttribute(img.source));
    Imf::FrameBuffer frame;
    const size_t x_stride = sizeof(float) * img.channels, y_stride = x_stride * img.width;
    for (int c = 0; c < img.channels; ++c) {
        header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        char* base = reinterpret_cast<char*>(const_cast<float*>(img.data.data() + c));
        frame.insert(names[c], Imf::Slice(Imf::FLOAT, base, x_stride, y_stride));
    }
    write_atomically(path, [&](const std::string& tmp) {
        Imf::OutputFile file(tmp.c_str(), header);
        file.setFrameBuffer(frame);
        file.writePixels(img.height);
    });
}

namespace {
template <typename Encode>
void write_png8(const std::string& path, const Image& img, Encode encode) {
    // Readers tell a picture's kind by its name: PNG bytes in "v.exr" would read as linear.
    if (lower_extension(path) != ".png")
        throw std::invalid_argument(path + ": a PNG file is written here; its name must end in .png");
    std::vector<uint8_t> px(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
        for (int c = 0; c < 3; ++c) {
            float v = img.data[i * img.channels + std::min(c, img.channels - 1)];
            px[i * 3 + c] = uint8_t(std::lround(255.f * encode(std::isfinite(v) ? v : 0.f)));
        }
    write_atomically(path, [&](const std::string& tmp) {
        png_image png{};
        png.version = PNG_IMAGE_VERSION;
        png.width = png_uint_32(img.width);
        png.height = png_uint_32(img.height);
        png.format = PNG_FORMAT_RGB;
        if (!png_image_write_to_file(&png, tmp.c_str(), 0, px.data(), 0, nullptr)) {
            const std::string message = png.message;
            png_image_free(&png);
            throw std::runtime_error(message);
        }
    });
}
}  // namespace

void write_png_srgb(const std::string& path, const Image& img, float exposure) {
    const float scale = std::exp2(exposure);
    write_png8(path, img, [scale](float v) { return linear_to_srgb(v * scale); });
}

void write_png_display(const std::string& path, const Image& img) {
    write_png8(path, img, [](float v) { return std::clamp(v, 0.f, 1.f); });
}

Image read_image(const std::string& path) {
    std::unique_ptr<ImageFileReader> in = open_image_file(path);
    const ImageFileInfo& info = in->info();
    Image img;
    img.width = info.width;
    img.height = info.height;
    img.channels = info.channels;
    img.channel_names = info.channel_names;
    img.display = info.display_values;
    img.source = info.source;
    // The header's size is checked before anything is allocated from it.
    try {
        check_image_fits(img.width, img.height, size_t(std::max(img.channels, 1)));
    } catch (const std::length_error& e) {
        throw std::runtime_error(path + ": " + e.what());
    }
    img.data.resize(size_t(img.width) * img.height * img.channels);
    in->read_float(img.data.data());
    reorder_numbered_channels(img);
    return img;
}

std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw SceneError(path, "", "cannot open file");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

void require_finite_pixels(const Image& img, const std::string& path) {
    for (size_t i = 0; i < img.data.size(); ++i)
        if (!std::isfinite(img.data[i])) {
            const size_t c = size_t(std::max(img.channels, 1)), pixel = i / c;
            throw std::runtime_error(path + ": value at pixel (" + std::to_string(pixel % size_t(img.width)) + ", " +
                                     std::to_string(pixel / size_t(img.width)) + "), channel " + std::to_string(i % c) +
                                     " is not finite");
        }
}

void write_text_atomic(const std::string& path, const std::string& contents) {
    write_atomically(
        path,
        [&](const std::string& tmp) {
            std::ofstream out(tmp, std::ios::binary);
            out << contents;
            // short contents reach the disk only when the stream is flushed: a full disk shows
            // there, and a file cut short must not be renamed into place
            out.close();
            if (!out) throw std::runtime_error("the write did not complete");
        },
        "file");
}

void copy_file_atomic(const std::string& from, const std::string& to) {
    write_atomically(
        to, [&](const std::string& tmp) { fs::copy_file(from, tmp, fs::copy_options::overwrite_existing); },
        "a copy of its file");
}

}  // namespace lpt
