// Bitmap loading (OpenImageIO through core/image_reader.h), the process-wide bitmap cache, lookups, and the Props glue.
// Lookups follow Dr.Jit's dr::Texture as used by Mitsuba 3's bitmap plugin: bilinear at
// uv·size − 0.5 between the four surrounding pixel centres, nearest at floor(uv·size), each
// pixel index wrapped on its own.
#include "core/texture.h"
#include "core/error.h"
#include "core/film.h"
#include "core/image_reader.h"
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>

namespace lpt {

namespace fs = std::filesystem;

namespace {

/// The exact sRGB EOTF (IEC 61966-2-1), in double so the 8-bit table is correctly rounded.
double srgb_to_linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

/// "<path>: message" -> "message" (SceneError puts the path in front again).
std::string strip_path(const std::string& what, const std::string& path) {
    return what.rfind(path + ": ", 0) == 0 ? what.substr(path.size() + 2) : what;
}

std::shared_ptr<const BitmapData> decode(const std::string& path, bool raw) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw SceneError(path, "", "cannot open image file (missing or not a file)");
    // Mitsuba drops alpha and keeps the colour as stored, so ask for unassociated alpha.
    std::unique_ptr<ImageFileReader> in;
    try {
        in = open_image_file(path, true);
    } catch (const std::runtime_error& e) {
        throw SceneError(path, "", strip_path(e.what(), path));
    }
    const ImageFileInfo& info = in->info();
    const int w = info.width, h = info.height, nc = info.channels;
    if (w <= 0 || h <= 0 || info.depth > 1) throw SceneError(path, "", "image is empty or not 2D");
    if (nc < 1 || nc > 4)
        throw SceneError(path, "",
                         "image has " + std::to_string(nc) + " channels (expected 1 to 4: Y, YA, RGB or RGBA)");
    try {
        check_image_fits(w, h, size_t(nc));
    } catch (const std::length_error& e) {
        throw SceneError(path, "", e.what());
    }
    const bool srgb = !info.is_float && !raw;  // Mitsuba 3: JPEG/PNG data is sRGB, EXR/HDR linear

    const size_t n = size_t(w) * size_t(h);
    std::vector<float> px(n * size_t(nc));
    try {
        if (info.is_uint8) {
            // Exact per-code conversion: a 256-entry table instead of float rounding of v/255.
            std::vector<uint8_t> bytes(px.size());
            in->read_uint8(bytes.data());
            std::array<float, 256> lut;
            for (int i = 0; i < 256; ++i) lut[i] = float(srgb ? srgb_to_linear(i / 255.0) : i / 255.0);
            for (size_t i = 0; i < px.size(); ++i) px[i] = lut[bytes[i]];
        } else {
            // Other integer types come back normalised to [0, 1]; floats as stored.
            in->read_float(px.data());
            if (srgb)
                for (float& v : px) v = float(srgb_to_linear(v));
        }
    } catch (const std::runtime_error& e) {
        throw SceneError(path, "", strip_path(e.what(), path));
    }
    in.reset();

    auto out = std::make_shared<BitmapData>();
    out->path = path;
    out->width = w;
    out->height = h;
    out->rgb.resize(3 * n);
    const bool grey = nc <= 2;  // Y or YA
    Eigen::Array3d sum = Eigen::Array3d::Zero();
    for (size_t i = 0; i < n; ++i) {
        const float* p = &px[i * size_t(nc)];
        for (int c = 0; c < 3; ++c) {
            float v = p[grey ? 0 : c];
            if (!std::isfinite(v))
                throw SceneError(path, "",
                                 "pixel (" + std::to_string(i % size_t(w)) + ", " + std::to_string(i / size_t(w)) +
                                     ") is not finite");
            out->rgb[3 * i + c] = v;
            sum[c] += v;
        }
    }
    out->mean = (sum / double(n)).cast<float>();
    return out;
}

struct CacheEntry {
    std::shared_ptr<const BitmapData> data;
    fs::file_time_type mtime;
    uintmax_t size = 0;
};

/// Loads through the cache. Keyed by canonical path and raw; an entry is reloaded if the file's
/// size or modification time changed, so a rewritten image is never served stale. Entries are
/// kept for the process's lifetime: scene textures are few and are needed again for every
/// BSDF rebuild. Loading happens under the lock, which also keeps two threads from decoding
/// the same file at once.
std::shared_ptr<const BitmapData> cached_bitmap(const std::string& path, bool raw) {
    static std::mutex mutex;
    static std::map<std::pair<std::string, bool>, CacheEntry> cache;
    std::error_code ec;
    fs::path canon = fs::weakly_canonical(path, ec);
    std::string key = ec ? path : canon.string();
    fs::file_time_type mtime = fs::last_write_time(path, ec);
    uintmax_t size = ec ? 0 : fs::file_size(path, ec);
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find({key, raw});
    if (it != cache.end() && !ec && it->second.mtime == mtime && it->second.size == size) return it->second.data;
    CacheEntry e{decode(path, raw), mtime, size};
    cache[{key, raw}] = e;
    return e.data;
}

int64_t wrap_index(int64_t i, int64_t n, TextureWrap mode) {
    switch (mode) {
        case TextureWrap::Clamp:
            return std::clamp<int64_t>(i, 0, n - 1);
        case TextureWrap::Mirror: {  // period 2n: 0..n-1 then n-1..0
            int64_t m = i % (2 * n);
            if (m < 0) m += 2 * n;
            return m < n ? m : 2 * n - 1 - m;
        }
        case TextureWrap::Repeat:
        default: {
            int64_t m = i % n;
            return m < 0 ? m + n : m;
        }
    }
}

/// floor(x) as an integer; x is clamped first so huge uvs cannot overflow the conversion
/// (any index that far out wraps to an arbitrary but valid pixel, as in float arithmetic).
/// Errors name the owner's field (`materials.wood.reflectance.filter_type`), whatever `where`
/// the texture's own Props was given.
[[noreturn]] void fail_texture_field(const Props& owner, const std::string& key, const std::string& sub,
                                     const std::string& msg) {
    owner.fail(key + "." + sub, msg);
}

int64_t floor_index(float x) { return int64_t(std::floor(std::clamp(x, -1e15f, 1e15f))); }

}  // namespace

Texture::Texture(std::shared_ptr<const BitmapData> bitmap, TextureFilter filter, TextureWrap wrap)
    : m_constant(bitmap ? bitmap->mean : Eigen::Array3f::Zero()),
      m_bitmap(std::move(bitmap)),
      m_filter(filter),
      m_wrap(wrap) {}

Texture Texture::load_bitmap(const std::string& path, bool raw, TextureFilter filter, TextureWrap wrap) {
    return Texture(cached_bitmap(path, raw), filter, wrap);
}

Eigen::Array3f Texture::eval(const Vec2f& uv) const {
    if (!m_bitmap) return m_constant;
    const BitmapData& b = *m_bitmap;
    if (!uv.allFinite()) return Eigen::Array3f::Zero();  // cannot happen for validated meshes
    const int64_t w = b.width, h = b.height;
    if (m_filter == TextureFilter::Nearest) {
        int64_t x = wrap_index(floor_index(uv.x() * float(w)), w, m_wrap);
        int64_t y = wrap_index(floor_index(uv.y() * float(h)), h, m_wrap);
        return b.pixel(int(x), int(y));
    }
    const float fx = uv.x() * float(w) - 0.5f, fy = uv.y() * float(h) - 0.5f;
    const int64_t x0 = floor_index(fx), y0 = floor_index(fy);
    const float ax = fx - float(x0), ay = fy - float(y0);  // weights of the +1 neighbours
    const int xa = int(wrap_index(x0, w, m_wrap)), xb = int(wrap_index(x0 + 1, w, m_wrap));
    const int ya = int(wrap_index(y0, h, m_wrap)), yb = int(wrap_index(y0 + 1, h, m_wrap));
    return (1.f - ay) * ((1.f - ax) * b.pixel(xa, ya) + ax * b.pixel(xb, ya)) +
           ay * ((1.f - ax) * b.pixel(xa, yb) + ax * b.pixel(xb, yb));
}

Texture texture_from_props(const Props& owner, const std::string& key, const Eigen::Array3f& default_rgb) {
    owner.mark_queried(key);
    auto it = owner.values.find(key);
    if (it == owner.values.end()) return Texture(default_rgb);
    const PropValue& v = it->second;
    if (std::holds_alternative<float>(v) || std::holds_alternative<Eigen::Array3f>(v))
        return Texture(owner.get_rgb(key, default_rgb));
    const auto* child = std::get_if<std::shared_ptr<Props>>(&v);
    if (!child || !*child) owner.fail(key, "expected an rgb triple, a number or a bitmap texture");
    const Props& t = **child;
    if (t.type != "bitmap") owner.fail(key + ".type", "unknown texture type '" + t.type + "' (known: bitmap)");

    auto fail = [&](const std::string& sub, const std::string& msg) { fail_texture_field(owner, key, sub, msg); };
    auto str = [&](const char* name, const std::string& def) -> std::string {
        auto f = t.values.find(name);
        if (f == t.values.end()) return def;
        if (auto* s = std::get_if<std::string>(&f->second)) return *s;
        fail_texture_field(owner, key, name, "expected a string");
    };
    for (const auto& [k, unused] : t.values) {
        if (k != "filename" && k != "raw" && k != "filter_type" && k != "wrap_mode")
            fail(k, "bitmap texture does not support '" + k + "' (supported: filename, raw, filter_type, wrap_mode)");
        t.mark_queried(k);
    }

    if (!t.has("filename")) fail("filename", "a bitmap texture needs a filename");
    fs::path file = str("filename", "");
    if (file.empty()) fail("filename", "is empty");
    if (file.is_relative() && !owner.file.empty()) file = fs::path(owner.file).parent_path() / file;

    bool raw = false;
    if (auto f = t.values.find("raw"); f != t.values.end()) {
        const bool* b = std::get_if<bool>(&f->second);
        if (!b) fail("raw", "expected a boolean");
        raw = *b;
    }
    std::string fs_name = str("filter_type", "bilinear"), wm = str("wrap_mode", "repeat");
    TextureFilter filter = TextureFilter::Bilinear;
    if (fs_name == "nearest") filter = TextureFilter::Nearest;
    else if (fs_name != "bilinear") fail("filter_type", "expected bilinear or nearest, got '" + fs_name + "'");
    TextureWrap wrap = TextureWrap::Repeat;
    if (wm == "mirror") wrap = TextureWrap::Mirror;
    else if (wm == "clamp") wrap = TextureWrap::Clamp;
    else if (wm != "repeat") fail("wrap_mode", "expected repeat, mirror or clamp, got '" + wm + "'");

    try {
        return Texture::load_bitmap(file.string(), raw, filter, wrap);
    } catch (const SceneError& e) {
        fail_texture_field(owner, key, "filename", e.what());  // the message starts with the image's path
    }
}

namespace {

/// Finds the bitmap-holding field of `p` (or a nested child) whose error field name is `field`.
const Props* owner_of_texture_field(const Props& p, const std::string& field, std::string& key) {
    for (const auto& [k, v] : p.values) {
        const auto* child = std::get_if<std::shared_ptr<Props>>(&v);
        if (!child || !*child) continue;
        const std::string f = p.where.empty() ? k : p.where + "." + k;
        if ((*child)->type == "bitmap" && field == f) {
            key = k;
            return &p;
        }
        if (const Props* o = owner_of_texture_field(**child, field, key)) return o;
    }
    return nullptr;
}

}  // namespace

SceneError explain_texture_error(const Props& props, const SceneError& e) {
    std::string key;
    const Props* owner = owner_of_texture_field(props, e.field(), key);
    if (!owner || owner->file != e.file()) return e;
    return SceneError(e.file(), e.field(), "textured " + key + " on " + owner->type + " is not supported yet");
}

}  // namespace lpt
