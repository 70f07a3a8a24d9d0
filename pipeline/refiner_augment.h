// Augmented training pairs for the refiner, made from the training view alone: the same view
// seen through a camera rolled by quarter turns, the view of the world mirrored across the
// camera's vertical plane, and (shift) renders through the film moved by half a latent pixel.
// Each is an exact pair of the refiner's mapping: the rendered latent and AOVs of the new view are
// those of the training view moved in the image (world normals reflected for the mirror; a new
// render for a shift), and its target is the VAE's encoding of the reference image moved the same
// way. The VAE is not equivariant (on cbox-specular's training view enc(mirror(I)) differs from
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
    Shift,     ///< and renders with the film moved by half a latent pixel (film_shifts)
};
/// "none" | "mirror" | "dihedral" | "shift"
RefinerAugment parse_refiner_augment(const std::string& name);
std::string to_string(RefinerAugment a);

/// A move of the image: first a left-right mirror (when `mirror`), then `quarter_turns` turns of
/// 90° clockwise. Odd turns swap width and height.
struct ViewTransform {
    int quarter_turns = 0;
    bool mirror = false;
    /// Whether the moved image is h × w (odd turns) rather than w × h.
    bool swaps_axes() const { return quarter_turns % 2 != 0; }
};

/// The identity first, then the other transforms of the augmentation (shift has none: its views
/// are new renders, film_shifts).
std::vector<ViewTransform> augment_transforms(RefinerAugment a);

/// A move of the film by whole pixels of the RGB image (x to the right, y down): the latent
/// pixel (i, j) of a render through the moved film covers the reference's pixels
/// [8i + x, 8i + x + 8) × [8j + y, 8j + y + 8).
struct FilmShift {
    int x = 0, y = 0;
};
/// The shift augmentation's moves: half a latent pixel (4 RGB pixels) right, down, and both. The
/// training view shows every edge at one phase against the 8 × 8 grid of latent cells; these show
/// the same edges at the other half-phases, where an edited view's edges fall anywhere.
std::vector<FilmShift> film_shifts();
/// The camera whose film is moved by (fx, fy) of its width and height: pixel (i, j) at any
/// resolution W × H sees what film position (i + fx W, j + fy H) sees through `c`. A shear of
/// camera space (x += a z, y += b z), so the rays stay those of a pinhole at the same origin.
Camera film_shifted(const Camera& c, float fx, float fy);
/// The w × h window of a view from pixel (x0, y0): its latent, AOVs and terms.
RefinerInput crop_view(const RefinerInput& in, int x0, int y0, int w, int h);
/// The w × h × c window of an image (row-major from the top-left) from pixel (x0, y0).
std::vector<float> crop_image(const std::vector<float>& image, int width, int c, int x0, int y0, int w, int h);

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
