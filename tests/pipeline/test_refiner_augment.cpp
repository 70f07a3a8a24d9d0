// The refiner's augmented views (pipeline/refiner_augment.h): pixels move as written by hand,
// the eight moves are the dihedral group, the RGB image (8× the latent's size) and the latent
// move alike, and each move is what the renderer sees: a camera rolled by a quarter turn renders
// the turned AOVs, and the world mirrored across the camera's vertical plane renders the mirrored
// AOVs with reflected normals.
#include "core/scene.h"
#include "core/scene_loader.h"
#include "core/scene_spectra.h"
#include "integrators/aov.h"
#include "pipeline/refiner_augment.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>
#include <set>

using namespace lpt;
using pipeline::RefinerAugment;
using pipeline::transform_image;
using pipeline::transform_view;
using pipeline::ViewTransform;

namespace {

const std::string kCornell = std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json";

std::vector<float> random_image(int w, int h, int c, uint64_t seed) {
    return test::random_weights(size_t(w) * size_t(h) * size_t(c), seed);
}

/// Mean over f × f blocks (how a latent pixel covers its 8 × 8 RGB pixels).
std::vector<float> box_down(const std::vector<float>& img, int w, int h, int c, int f) {
    const int ow = w / f, oh = h / f;
    std::vector<float> out(size_t(ow) * size_t(oh) * size_t(c), 0.f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < c; ++k)
                out[(size_t(y / f) * size_t(ow) + size_t(x / f)) * size_t(c) + size_t(k)] +=
                    img[(size_t(y) * size_t(w) + size_t(x)) * size_t(c) + size_t(k)] / float(f * f);
    return out;
}

RefinerInput aov_view(const Scene& scene, int w, int h) {
    const AovImages aov = render_aovs(scene, SceneSpectra<3>::from_description(scene), w, h, 64, 3);
    RefinerInput in;
    in.width = w;
    in.height = h;
    in.latent.assign(size_t(w) * size_t(h), 0.f);  // one channel: the AOVs are what is compared
    in.normal = aov.normal;
    in.distance = aov.distance;
    return in;
}

/// Mean absolute difference of two buffers of one size.
double mean_abs(const std::vector<float>& a, const std::vector<float>& b) {
    EXPECT_EQ(a.size(), b.size());
    double s = 0;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i) s += std::abs(double(a[i]) - double(b[i]));
    return s / double(a.size());
}

}  // namespace

TEST(RefinerAugment, PixelsMoveAsWrittenByHand) {
    // 3 × 2:  0 1 2
    //         3 4 5
    const std::vector<float> img = {0, 1, 2, 3, 4, 5};
    EXPECT_EQ(transform_image(img, 3, 2, 1, {1, false}), (std::vector<float>{3, 0, 4, 1, 5, 2}));  // 2 × 3
    EXPECT_EQ(transform_image(img, 3, 2, 1, {2, false}), (std::vector<float>{5, 4, 3, 2, 1, 0}));
    EXPECT_EQ(transform_image(img, 3, 2, 1, {3, false}), (std::vector<float>{2, 5, 1, 4, 0, 3}));
    EXPECT_EQ(transform_image(img, 3, 2, 1, {0, true}), (std::vector<float>{2, 1, 0, 5, 4, 3}));
    EXPECT_EQ(transform_image(img, 3, 2, 1, {1, true}), (std::vector<float>{5, 2, 4, 1, 3, 0}));  // mirror, then turn
    // Channels travel with their pixel.
    EXPECT_EQ(transform_image({0, 10, 1, 11}, 2, 1, 2, {0, true}), (std::vector<float>{1, 11, 0, 10}));
    EXPECT_THROW(transform_image(img, 4, 2, 1, {}), std::invalid_argument);
    EXPECT_THROW(pipeline::parse_refiner_augment("flip"), std::invalid_argument);
}

TEST(RefinerAugment, TheMovesAreTheDihedralGroupAndMoveRgbAsTheLatent) {
    const int w = 5, h = 3;
    const std::vector<float> img = random_image(w, h, 2, 1);
    std::vector<float> turned = img;
    for (int k = 0; k < 4; ++k) turned = transform_image(turned, k % 2 ? h : w, k % 2 ? w : h, 2, {1, false});
    EXPECT_EQ(turned, img);
    const std::vector<float> mirrored = transform_image(img, w, h, 2, {0, true});
    EXPECT_EQ(transform_image(mirrored, w, h, 2, {0, true}), img);

    ASSERT_EQ(pipeline::augment_transforms(RefinerAugment::None).size(), 1u);
    ASSERT_EQ(pipeline::augment_transforms(RefinerAugment::Mirror).size(), 2u);
    const std::vector<ViewTransform> all = pipeline::augment_transforms(RefinerAugment::Dihedral);
    ASSERT_EQ(all.size(), 8u);
    EXPECT_EQ(all[0].quarter_turns, 0);
    EXPECT_FALSE(all[0].mirror);
    std::set<std::vector<float>> distinct;
    for (const ViewTransform& t : all) distinct.insert(transform_image(img, w, h, 2, t));
    EXPECT_EQ(distinct.size(), 8u);

    // An 8× image moved, then averaged over 8 × 8 blocks, is the averaged image moved: the RGB
    // reference and the latent-resolution buffers stay registered under every move.
    const std::vector<float> rgb = random_image(8 * w, 8 * h, 3, 2);
    for (const ViewTransform& t : all) {
        const bool swap = t.swaps_axes();
        const std::vector<float> a =
            box_down(transform_image(rgb, 8 * w, 8 * h, 3, t), swap ? 8 * h : 8 * w, swap ? 8 * w : 8 * h, 3, 8);
        const std::vector<float> b = transform_image(box_down(rgb, 8 * w, 8 * h, 3, 8), w, h, 3, t);
        ASSERT_EQ(a.size(), b.size());
        for (size_t i = 0; i < a.size(); ++i)
            ASSERT_NEAR(a[i], b[i], 1e-5) << "turns " << t.quarter_turns << " mirror " << t.mirror;
    }
}

TEST(RefinerAugment, MirrorReflectsNormalsAcrossTheCameraPlaneAndTurnsKeepThem) {
    RefinerInput in;
    in.width = 2;
    in.height = 1;
    in.latent = {1, 2, 3, 4};  // two channels
    in.normal = {0.6f, 0.f, 0.8f, 0.f, 1.f, 0.f};
    in.distance = {5, 7};
    const Vec3f right = Vec3f(1, 1, 0).normalized();
    const RefinerInput m = transform_view(in, {0, true}, right);
    EXPECT_EQ(m.latent, (std::vector<float>{3, 4, 1, 2}));
    EXPECT_EQ(m.distance, (std::vector<float>{7, 5}));
    for (int p = 0; p < 2; ++p) {
        const Vec3f before(in.normal[3 * (1 - p)], in.normal[3 * (1 - p) + 1], in.normal[3 * (1 - p) + 2]);
        const Vec3f after(m.normal[3 * p], m.normal[3 * p + 1], m.normal[3 * p + 2]);
        EXPECT_NEAR(after.dot(right), -before.dot(right), 1e-6);
        EXPECT_NEAR((after - after.dot(right) * right - (before - before.dot(right) * right)).norm(), 0.0, 1e-6);
    }
    const RefinerInput t = transform_view(in, {1, false}, right);
    EXPECT_EQ(t.width, 1);
    EXPECT_EQ(t.height, 2);
    EXPECT_EQ(t.normal, in.normal);  // a rolled camera sees the same world normals
}

// What the renderer sees. Rolling the camera by a quarter turn about its view axis turns the
// image by a quarter turn, one way or the other; the test finds which from the renders and
// requires one to match within sampling noise and the other not. The mirrored world (every mesh
// reflected across the plane through the camera's origin with normal mirror_plane_normal, which
// maps the camera onto itself) must render as transform_view's mirror, reflected normals included.
TEST(RefinerAugment, RolledCameraAndMirroredWorldRenderTheMovedViews) {
    const int n = 24;
    Scene scene = load_scene(kCornell);
    const RefinerInput view = aov_view(scene, n, n);
    const Vec3f right = pipeline::mirror_plane_normal(scene.camera);

    Scene rolled = load_scene(kCornell);
    rolled.camera.world_from_camera = rolled.camera.world_from_camera * Transform::rotate(Vec3f::UnitZ(), 90.f);
    const RefinerInput roll = aov_view(rolled, n, n);
    double err[2];
    for (int k = 0; k < 2; ++k) {
        const RefinerInput moved = transform_view(view, {k == 0 ? 1 : 3, false}, right);
        err[k] = mean_abs(moved.distance, roll.distance) + mean_abs(moved.normal, roll.normal);
    }
    const double match = std::min(err[0], err[1]), other = std::max(err[0], err[1]);
    EXPECT_LT(match, 0.05) << "quarter turns 1 / 3: " << err[0] << " / " << err[1];
    EXPECT_GT(other, 10 * match) << "quarter turns 1 / 3: " << err[0] << " / " << err[1];

    Scene mirrored = load_scene(kCornell);
    const Vec3f o = mirrored.camera.world_from_camera.point(Vec3f::Zero());
    Eigen::Matrix4f reflect = Eigen::Matrix4f::Identity();
    reflect.topLeftCorner<3, 3>() -= 2.f * right * right.transpose();
    reflect.topRightCorner<3, 1>() = 2.f * o.dot(right) * right;
    for (Shape& s : mirrored.shapes) s.mesh.transform(Transform(reflect));
    mirrored.build();
    const RefinerInput mirror = aov_view(mirrored, n, n);
    const RefinerInput moved = transform_view(view, {0, true}, right);
    EXPECT_LT(mean_abs(moved.distance, mirror.distance), 0.02);
    EXPECT_LT(mean_abs(moved.normal, mirror.normal), 0.02);
    // Mirrored pixels with unreflected normals are wrong wherever a normal has a sideways part.
    const RefinerInput unreflected = transform_view(view, {0, true}, Vec3f::Zero());
    EXPECT_GT(mean_abs(unreflected.normal, mirror.normal), 0.1);
}

TEST(RefinerAugment, CropsTakeTheWindowWrittenByHand) {
    // 3 × 2, two channels:  (0,1) (2,3) (4,5)
    //                       (6,7) (8,9) (10,11)
    const std::vector<float> img = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    EXPECT_EQ(pipeline::crop_image(img, 3, 2, 1, 0, 2, 2), (std::vector<float>{2, 3, 4, 5, 8, 9, 10, 11}));
    EXPECT_EQ(pipeline::crop_image(img, 3, 2, 0, 1, 1, 1), (std::vector<float>{6, 7}));
    EXPECT_THROW(pipeline::crop_image(img, 3, 2, 2, 0, 2, 1), std::invalid_argument);
    RefinerInput in;
    in.width = 3;
    in.height = 2;
    in.latent = img;
    in.normal.assign(18, 0.f);
    in.distance = {1, 2, 3, 4, 5, 6};
    const RefinerInput c = pipeline::crop_view(in, 1, 1, 2, 1);
    EXPECT_EQ(c.width, 2);
    EXPECT_EQ(c.height, 1);
    EXPECT_EQ(c.latent, (std::vector<float>{8, 9, 10, 11}));
    EXPECT_EQ(c.distance, (std::vector<float>{5, 6}));
    EXPECT_EQ(c.normal.size(), 6u);
}

// The shift augmentation's camera: its film moved by one pixel's width (or height) renders, at
// pixel (i, j), what the unmoved camera renders at (i + 1, j) (or (i, j + 1)), within sampling
// noise, and not what it renders one pixel the other way. Distances and normals are compared: the
// ray origin is kept, so the depth of each pixel is the same ray's.
TEST(RefinerAugment, FilmShiftRendersTheViewMovedByWholePixels) {
    const int n = 24;
    Scene scene = load_scene(kCornell);
    const RefinerInput view = aov_view(scene, n, n);
    for (int axis = 0; axis < 2; ++axis) {
        Scene moved = load_scene(kCornell);
        moved.camera = pipeline::film_shifted(moved.camera, axis == 0 ? 1.f / n : 0.f, axis == 1 ? 1.f / n : 0.f);
        const RefinerInput shifted = aov_view(moved, n, n);
        const int dx = axis == 0 ? 1 : 0, dy = axis == 1 ? 1 : 0;
        // the moved film's pixels 0 … n − 2 against the unmoved one's 1 … n − 1, and 0 … n − 2 (wrong way)
        const RefinerInput a = pipeline::crop_view(shifted, 0, 0, n - dx, n - dy);
        const RefinerInput ahead = pipeline::crop_view(view, dx, dy, n - dx, n - dy);
        const RefinerInput same = pipeline::crop_view(view, 0, 0, n - dx, n - dy);
        const double match = mean_abs(a.distance, ahead.distance) + mean_abs(a.normal, ahead.normal);
        const double stay = mean_abs(a.distance, same.distance) + mean_abs(a.normal, same.normal);
        EXPECT_LT(match, 0.03) << "axis " << axis;
        EXPECT_GT(stay, 3 * match) << "axis " << axis << ": the moved film renders the unmoved view";
    }
}
