// Augmented training pairs for the refiner, made from the training view alone: the same view
// seen through a camera rolled by quarter turns, and the view of the world mirrored across the
// camera's vertical plane. Each is an exact pair of the refiner's mapping: the rendered latent and
// AOVs of the new view are those of the training view moved in the image (world normals reflected
// for the mirror), and its target is the VAE's encoding of the reference image moved the same way.
// The VAE is not equivariant (on cbox-specular's training view enc(mirror(I)) differs from
// mirror(enc(I)) by latent MSE 0.028, the size of the rendered latent's own error), so the new
// targets are new information. docs/refiner.md "Augmentation".
#pragma once
#include "core/camera.h"
#include "core/geometry.h"
#include "refiner/refiner.h"
#include <string>
#include <vector>

namespace lpt::pipeline {

enum class RefinerAugment {
    None,      ///< the training view alone
    Mirror,    ///< and its mirror image
    Dihedral,  ///< the four quarter turns of both
};
RefinerAugment parse_refiner_augment(const std::string& name);  ///< "none" | "mirror" | "dihedral"
std::string to_string(RefinerAugment a);

/// A move of the image: first a left-right mirror (when `mirror`), then `quarter_turns` turns of
/// 90° clockwise. Odd turns swap width and height.
struct ViewTransform {
    int quarter_turns = 0;
    bool mirror = false;
    /// Whether the moved image is h × w (odd turns) rather than w × h.
    bool swaps_axes() const { return quarter_turns % 2 != 0; }
};

/// The identity first, then the other transforms of the augmentation.
std::vector<ViewTransform> augment_transforms(RefinerAugment a);

/// An image (w × h × c, row-major from the top-left) moved by t.
std::vector<float> transform_image(const std::vector<float>& image, int w, int h, int c, ViewTransform t);
/// The refiner's input of the moved view: latent, normals and distances moved as images; with a
/// mirror, each normal is also reflected across the plane whose normal is `camera_right` (the
/// camera's x axis in world space, unit length), as the mirrored world's normals are.
RefinerInput transform_view(const RefinerInput& in, ViewTransform t, const Vec3f& camera_right);
/// The camera's x axis in world space, unit length: the normal of the plane through the camera
/// that a mirrored view reflects the world across (it maps the camera onto itself).
Vec3f mirror_plane_normal(const Camera& camera);

}  // namespace lpt::pipeline
