// Texture: an RGB value that is either constant or looked up in a bitmap by surface uv, for
// BSDF parameters such as diffuse `reflectance` (Mitsuba 3's `bitmap` texture). Bitmaps hold
// linear float RGB; 8- and 16-bit files are decoded from sRGB unless `raw`. Loaded bitmaps are
// shared through a process-wide cache, since one image typically serves several materials and
// every BSDF is built more than once (N = 3 for validation and rendering, N = 16 for latents).
//
// Orientation (as Mitsuba 3, whose bitmap does no flip of its own): u runs left to right along
// the image's width, v top to bottom down its rows, pixel (i, j) has its centre at
// ((i + 0.5)/w, (j + 0.5)/h), and v = 0 is the first row of the file (its top as displayed).
// OBJ `vt` coordinates have v pointing up, which is why Mitsuba's obj loader (and ours with
// flip_v / `flip_tex_coords`) stores v' = 1 - v: a vt of (0, 1) lands on the image's top-left.
#pragma once
#include "core/geometry.h"
#include "core/props.h"
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace lpt {

enum class TextureFilter { Bilinear, Nearest };
/// How uv outside [0, 1] is mapped back into the image (applied to pixel indices, as Dr.Jit's
/// texture does, so bilinear lookups near an edge blend with the wrapped neighbour).
enum class TextureWrap { Repeat, Mirror, Clamp };

/// Decoded image data; immutable once loaded, so cache entries can be shared between threads.
struct BitmapData {
    std::string path;
    int width = 0, height = 0;
    std::vector<float> rgb;  ///< linear RGB, 3 floats per pixel, rows from the top of the image
    Eigen::Array3f mean = Eigen::Array3f::Zero();
    Eigen::Array3f pixel(int x, int y) const {
        const float* p = &rgb[3 * (size_t(y) * size_t(width) + size_t(x))];
        return Eigen::Array3f(p[0], p[1], p[2]);
    }
};

class Texture {
public:
    explicit Texture(const Eigen::Array3f& constant = Eigen::Array3f::Zero()) : m_constant(constant) {}
    Texture(std::shared_ptr<const BitmapData> bitmap, TextureFilter filter, TextureWrap wrap);

    /// Reads an image through OpenImageIO (cached by resolved path and `raw`). Integer formats
    /// (8/16-bit JPEG, PNG, ...) are sRGB-encoded and linearised by the exact sRGB EOTF unless
    /// raw; float and half images (EXR, HDR) are linear. Grey broadcasts to RGB; alpha is
    /// dropped (not multiplied in). Throws SceneError(path, ...) if it cannot be read.
    static Texture load_bitmap(const std::string& path, bool raw = false,
                               TextureFilter filter = TextureFilter::Bilinear, TextureWrap wrap = TextureWrap::Repeat);

    bool is_constant() const { return !m_bitmap; }
    Eigen::Array3f eval(const Vec2f& uv) const;
    /// Average colour over the image's pixels (the constant itself for a constant texture); a
    /// stand-in where one colour is needed (latent channels, albedo of a whole material).
    Eigen::Array3f mean() const { return m_bitmap ? m_bitmap->mean : m_constant; }
    const std::shared_ptr<const BitmapData>& bitmap() const { return m_bitmap; }
    TextureFilter filter() const { return m_filter; }
    TextureWrap wrap() const { return m_wrap; }

private:
    Eigen::Array3f m_constant;
    std::shared_ptr<const BitmapData> m_bitmap;
    TextureFilter m_filter = TextureFilter::Bilinear;
    TextureWrap m_wrap = TextureWrap::Repeat;
};

/// `owner.values[key]` as a texture: a number or rgb gives a constant, a nested Props of type
/// "bitmap" (keys: filename, raw = false, filter_type = "bilinear" | "nearest", wrap_mode =
/// "repeat" | "mirror" | "clamp") a bitmap, a missing key `default_rgb`. A relative filename is
/// taken relative to owner.file's folder (loaders store it resolved already). Anything else,
/// and an unreadable image, is a SceneError naming owner.file and the field.
Texture texture_from_props(const Props& owner, const std::string& key, const Eigen::Array3f& default_rgb);

/// For loaders: `e` was thrown while building a plugin from `props`. If it concerns a field that
/// holds a bitmap texture (in `props` or a nested child), the plugin read that field as a plain
/// value, i.e. it does not take textures there: returns "textured <key> on <type> is not
/// supported yet" for the same file and field. Otherwise returns `e` unchanged.
SceneError explain_texture_error(const Props& props, const SceneError& e);

}  // namespace lpt
