#include "pipeline/refiner_augment.h"
#include <stdexcept>

namespace lpt::pipeline {

RefinerAugment parse_refiner_augment(const std::string& name) {
    if (name == "none") return RefinerAugment::None;
    if (name == "mirror") return RefinerAugment::Mirror;
    if (name == "dihedral") return RefinerAugment::Dihedral;
    if (name == "shift") return RefinerAugment::Shift;
    throw std::invalid_argument("refiner augmentation '" + name + "': expected none, mirror, dihedral or shift");
}

std::string to_string(RefinerAugment a) {
    switch (a) {
        case RefinerAugment::Mirror:
            return "mirror";
        case RefinerAugment::Dihedral:
            return "dihedral";
        case RefinerAugment::Shift:
            return "shift";
        default:
            return "none";
    }
}

std::vector<ViewTransform> augment_transforms(RefinerAugment a) {
    std::vector<ViewTransform> ts = {{0, false}};
    if (a == RefinerAugment::None || a == RefinerAugment::Shift) return ts;
    ts.push_back({0, true});
    if (a == RefinerAugment::Mirror) return ts;
    for (int turns = 1; turns < 4; ++turns)
        for (bool mirror : {false, true}) ts.push_back({turns, mirror});
    return ts;
}

namespace {

/// The source pixel (x, y) of output pixel (ox, oy) under t, for a source of w × h.
void source_pixel(ViewTransform t, int w, int h, int ox, int oy, int& x, int& y) {
    // Undo the clockwise turns, last first: pixel (ox, oy) after a turn of an image of height hh
    // came from (oy, hh − 1 − ox). After k turns the image is w × h for even k, h × w for odd k.
    x = ox;
    y = oy;
    for (int k = ((t.quarter_turns % 4) + 4) % 4; k > 0; --k) {
        const int height_before = (k - 1) % 2 ? w : h;
        const int sx = y, sy = height_before - 1 - x;
        x = sx;
        y = sy;
    }
    if (t.mirror) x = w - 1 - x;
}

}  // namespace

std::vector<float> transform_image(const std::vector<float>& image, int w, int h, int c, ViewTransform t) {
    if (image.size() != size_t(w) * size_t(h) * size_t(c))
        throw std::invalid_argument("transform_image: buffer is not " + std::to_string(w) + "x" + std::to_string(h) +
                                    "x" + std::to_string(c));
    const int ow = t.swaps_axes() ? h : w, oh = t.swaps_axes() ? w : h;
    std::vector<float> out(image.size());
    for (int oy = 0; oy < oh; ++oy)
        for (int ox = 0; ox < ow; ++ox) {
            int x = 0, y = 0;
            source_pixel(t, w, h, ox, oy, x, y);
            const size_t from = (size_t(y) * size_t(w) + size_t(x)) * size_t(c);
            const size_t to = (size_t(oy) * size_t(ow) + size_t(ox)) * size_t(c);
            for (int k = 0; k < c; ++k) out[to + size_t(k)] = image[from + size_t(k)];
        }
    return out;
}

RefinerInput transform_view(const RefinerInput& in, ViewTransform t, const Vec3f& camera_right) {
    RefinerInput out;
    out.width = t.swaps_axes() ? in.height : in.width;
    out.height = t.swaps_axes() ? in.width : in.height;
    const int c = in.width * in.height > 0 ? int(in.latent.size() / (size_t(in.width) * size_t(in.height))) : 0;
    out.latent = transform_image(in.latent, in.width, in.height, c, t);
    out.normal = transform_image(in.normal, in.width, in.height, 3, t);
    out.distance = transform_image(in.distance, in.width, in.height, 1, t);
    if (!in.terms.empty()) out.terms = transform_image(in.terms, in.width, in.height, 3 * c, t);
    if (t.mirror)
        for (size_t i = 0; i + 2 < out.normal.size(); i += 3) {
            const Vec3f n(out.normal[i], out.normal[i + 1], out.normal[i + 2]);
            const Vec3f reflected = n - 2.f * n.dot(camera_right) * camera_right;
            for (int k = 0; k < 3; ++k) out.normal[i + size_t(k)] = reflected[k];
        }
    return out;
}

Vec3f mirror_plane_normal(const Camera& camera) { return camera.world_from_camera.vector(Vec3f::UnitX()).normalized(); }

std::vector<FilmShift> film_shifts() { return {{4, 0}, {0, 4}, {4, 4}}; }

Camera film_shifted(const Camera& c, float fx, float fy) {
    // Film position (px, py) looks along camera-space ((1 − 2 px / W) tx, (1 − 2 py / H) ty, 1)
    // (core/cameras/perspective.cpp); moving it by (fx W, fy H) adds (−2 fx tx, −2 fy ty) to that
    // direction's x and y per unit of z.
    const Vec2f t = c.tan_half_fov();
    Eigen::Matrix4f shear = Eigen::Matrix4f::Identity();
    shear(0, 2) = -2.f * fx * t.x();
    shear(1, 2) = -2.f * fy * t.y();
    Camera moved = c;
    moved.world_from_camera = c.world_from_camera * Transform(shear);
    return moved;
}

std::vector<float> crop_image(const std::vector<float>& image, int width, int c, int x0, int y0, int w, int h) {
    const int height = width > 0 && c > 0 ? int(image.size() / (size_t(width) * size_t(c))) : 0;
    if (x0 < 0 || y0 < 0 || w < 0 || h < 0 || x0 + w > width || y0 + h > height)
        throw std::invalid_argument("crop_image: window outside the image");
    std::vector<float> out;
    out.reserve(size_t(w) * size_t(h) * size_t(c));
    for (int y = y0; y < y0 + h; ++y) {
        const auto row = image.begin() + std::ptrdiff_t((size_t(y) * size_t(width) + size_t(x0)) * size_t(c));
        out.insert(out.end(), row, row + std::ptrdiff_t(size_t(w) * size_t(c)));
    }
    return out;
}

RefinerInput crop_view(const RefinerInput& in, int x0, int y0, int w, int h) {
    RefinerInput out;
    out.width = w;
    out.height = h;
    const size_t pixels = size_t(in.width) * size_t(in.height);
    out.latent = crop_image(in.latent, in.width, int(in.latent.size() / pixels), x0, y0, w, h);
    out.normal = crop_image(in.normal, in.width, 3, x0, y0, w, h);
    out.distance = crop_image(in.distance, in.width, 1, x0, y0, w, h);
    if (!in.terms.empty()) out.terms = crop_image(in.terms, in.width, int(in.terms.size() / pixels), x0, y0, w, h);
    if (!in.emitter.empty())
        out.emitter = crop_image(in.emitter, in.width, int(in.emitter.size() / pixels), x0, y0, w, h);
    return out;
}

}  // namespace lpt::pipeline
