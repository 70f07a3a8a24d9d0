#include "core/image_io.h"
#include "core/film.h"
#include "core/error.h"
#include <sstream>
#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace lpt {

namespace fs = std::filesystem;

namespace {
std::string temp_path_for(const std::string& path) {
    fs::path p(path);
    // Keep the extension last: OIIO chooses the format from it.
    return (p.parent_path() / ("." + p.stem().string() + ".tmp" + std::to_string(::getpid()) + p.extension().string()))
        .string();
}

void write_oiio(const std::string& path, const OIIO::ImageSpec& spec, const void* data) {
    if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
    std::string tmp = temp_path_for(path);
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw std::runtime_error(path + ": no image writer for this extension (" + OIIO::geterror() + ")");
    if (!out->open(tmp, spec) || !out->write_image(spec.format, data) || !out->close()) {
        std::string err = out->geterror();
        fs::remove(tmp);
        throw std::runtime_error(path + ": cannot write image: " + err);
    }
    fs::rename(tmp, path);
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

float linear_to_srgb(float v) {
    v = std::clamp(v, 0.f, 1.f);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

void write_exr(const std::string& path, const Image& img) {
    OIIO::ImageSpec spec(img.width, img.height, img.channels, OIIO::TypeDesc::FLOAT);
    if (!img.channel_names.empty()) {
        spec.channelnames = img.channel_names;
    } else if (img.channels > 4) {
        spec.channelnames.clear();
        // Zero-padded: EXR stores channels sorted by name, and C10 would come before C2.
        for (int c = 0; c < img.channels; ++c) spec.channelnames.push_back((c < 10 ? "C0" : "C") + std::to_string(c));
    }
    spec.attribute("compression", "zip");
    // No write time in the header (OpenEXR's writer adds one unless told otherwise): the same
    // pixels give the same file, so split jobs merge into exactly the files of one job.
    spec.attribute("DateTime", "");
    write_oiio(path, spec, img.data.data());
}

namespace {
template <typename Encode>
void write_png8(const std::string& path, const Image& img, Encode encode) {
    std::vector<uint8_t> px(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
        for (int c = 0; c < 3; ++c) {
            float v = img.data[i * img.channels + std::min(c, img.channels - 1)];
            px[i * 3 + c] = uint8_t(std::lround(255.f * encode(std::isfinite(v) ? v : 0.f)));
        }
    OIIO::ImageSpec spec(img.width, img.height, 3, OIIO::TypeDesc::UINT8);
    write_oiio(path, spec, px.data());
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
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw std::runtime_error(path + ": cannot read image: " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    Image img;
    img.width = spec.width;
    img.height = spec.height;
    img.channels = spec.nchannels;
    img.channel_names = spec.channelnames;
    // The header's size is checked before anything is allocated from it.
    try {
        check_image_fits(img.width, img.height, size_t(std::max(img.channels, 1)));
    } catch (const std::length_error& e) {
        throw std::runtime_error(path + ": " + e.what());
    }
    img.data.resize(size_t(img.width) * img.height * img.channels);
    if (!in->read_image(0, 0, 0, img.channels, OIIO::TypeDesc::FLOAT, img.data.data()))
        throw std::runtime_error(path + ": cannot decode image: " + in->geterror());
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

void write_text_atomic(const std::string& path, const std::string& contents) {
    if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
    std::string tmp = temp_path_for(path);
    {
        std::ofstream out(tmp, std::ios::binary);
        out << contents;
        if (!out) throw std::runtime_error(path + ": cannot write file");
    }
    fs::rename(tmp, path);
}

}  // namespace lpt
