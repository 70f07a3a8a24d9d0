// Light sampling and camera geometry.
#include "core/camera.h"
#include "core/emitter.h"
#include "core/sampler.h"
#include "core/light_sampler.h"
#include "core/scene_loader.h"
#include "scene_fixtures.h"
#include "test_util.h"
#include <gtest/gtest.h>

using namespace lpt;

namespace {
struct MeanSe {
    double mean, se;
};
/// Mean and standard error of f(ls) over n samples of `light` seen from ref, drawn with
/// sample_1d(seed, i, 0, 0..2).
template <typename F>
MeanSe light_sample_mean(const Shape& light, const Vec3f& ref, uint64_t seed, int n, F&& f) {
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        const uint32_t k = uint32_t(i);
        const LightSample ls = sample_area_light(
            light, ref, Eigen::Vector3f(sample_1d(seed, k, 0, 0), sample_1d(seed, k, 0, 1), sample_1d(seed, k, 0, 2)));
        const double v = f(ls);
        sum += v;
        sum2 += v * v;
    }
    const double mean = sum / n;
    return {mean, std::sqrt((sum2 / n - mean * mean) / n)};
}
}  // namespace

TEST(AreaLight, SamplePdfMatchesPdfAreaLight) {
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
    const Shape& light = scene.shapes[scene.find_shape("light")];
    Vec3f ref(0.1f, -0.2f, 0.f);
    for (uint32_t i = 0; i < 1000; ++i) {
        LightSample ls = sample_area_light(
            light, ref, Eigen::Vector3f(sample_1d(1, i, 0, 0), sample_1d(1, i, 0, 1), sample_1d(1, i, 0, 2)));
        ASSERT_TRUE(ls.valid());
        EXPECT_NEAR(ls.pdf, pdf_area_light(light, ref, ls.p, ls.n), 1e-4f * ls.pdf);
    }
}

TEST(AreaLight, InversePdfIntegratesSolidAngle) {
    // E[1/pdf] = solid angle subtended; for a centred rectangle at height h, the solid angle is
    // 4 atan(ab / (h sqrt(a^2 + b^2 + h^2))).
    const float a = 0.5f, b = 0.3f, h = 1.f;
    Scene scene = test::form_factor_scene(0.5f, 1.f, a, b, h);
    const Shape& light = scene.shapes[scene.find_shape("light")];
    const MeanSe s = light_sample_mean(light, Vec3f::Zero(), 2, 200000,
                                       [](const LightSample& ls) { return ls.valid() ? 1.0 / ls.pdf : 0.0; });
    double expected = 4 * std::atan(a * b / (h * std::sqrt(a * a + b * b + h * h)));
    EXPECT_NEAR(s.mean, expected, 4 * s.se + 1e-6);
}

TEST(AreaLight, SphereIrradianceMatchesClosedForm) {
    // A sphere of radiance L entirely above a receiver's horizon acts as a point source of
    // intensity pi r^2 L: E = pi L r^2 cos(theta) / d^2. NEE samples its whole mesh, so the far
    // half (facing away) must add nothing and the near half exactly E. Ours is a 64 x 128 mesh
    // whose area is 0.05 % short of the sphere's, inside the 0.2 % allowance.
    const Vec3f centre(0.3f, 0.2f, 2.f);
    const float r = 0.4f;
    const Scene scene = load_scene(test::write_temp_file("sphere_light.json", R"({
      "camera": {"fov": 40, "width": 8, "height": 8, "to_world": {"lookat": {"origin": [0,0,-4], "target": [0,0,0], "up": [0,1,0]}}},
      "materials": {"m": {"type": "diffuse", "reflectance": 0.5}},
      "shapes": [{"id": "ball", "type": "sphere", "material": "m", "center": [0.3, 0.2, 2], "radius": 0.4,
                  "emitter": {"type": "area", "radiance": 1}}]
    })"));
    const Shape& ball = scene.shapes[scene.find_shape("ball")];
    for (const Vec3f& normal : {Vec3f(0, 0, 1), Vec3f(std::sin(0.6f), 0, std::cos(0.6f))}) {
        const Vec3f to_centre = centre;  // the receiver sits at the origin
        const double d = to_centre.norm(), cos_theta = normal.dot(to_centre) / d;
        ASSERT_GT(normal.dot(to_centre), r) << "the sphere must be entirely above the horizon";
        // 2M samples, se ~0.12 %: the far half of them adds 0
        const MeanSe s = light_sample_mean(ball, Vec3f::Zero(), 3, 2000000, [&](const LightSample& ls) {
            return ls.valid() ? std::max(0.f, normal.dot(ls.wi)) / ls.pdf : 0.0;
        });
        const double expected = M_PI * r * r * cos_theta / (d * d);
        EXPECT_NEAR(s.mean, expected, 4 * s.se + 2e-3 * expected) << "receiver normal " << normal.transpose();
    }
}

TEST(AreaLight, BackSideEmitsNothing) {
    Scene scene = test::form_factor_scene(0.5f, 1.f, 0.5f, 0.3f, 1.f);
    const Shape& light = scene.shapes[scene.find_shape("light")];
    LightSample ls = sample_area_light(light, Vec3f(0, 0, 2), Eigen::Vector3f(0.3f, 0.4f, 0.5f));
    EXPECT_FALSE(ls.valid());
}

TEST(LightSampler, PmfSumsToOneAndFollowsPower) {
    Scene scene = load_scene(test::cornell_box_path());
    double sum = 0;
    for (size_t i = 0; i < scene.emitters.size(); ++i) sum += scene.lights.pmf(int(i));
    EXPECT_NEAR(sum, 1.0, 1e-6);
}

TEST(LightSampler, BatchEqualsOneByOne) {
    // The tracer draws NEE samples with sample_batch: it must return sample()'s floats for flat
    // triangle lights (vectorised geometry), a sphere light with interpolated normals and the
    // environment (both fall back to sample()), reference points on, behind and beside lights.
    const Scene scene = load_scene(test::write_temp_file("batch_lights.json", R"({
      "integrator": {"light_sampling": "uniform"},
      "camera": {"fov": 40, "width": 8, "height": 8, "to_world": {"lookat": {"origin": [0,0,4], "target": [0,0,0], "up": [0,1,0]}}},
      "materials": {"m": {"type": "diffuse", "reflectance": 0.5}},
      "shapes": [
        {"id": "quad", "type": "rectangle", "material": "m", "to_world": {"translate": [0, 0, 2]}, "flip_normals": true,
         "emitter": {"type": "area", "radiance": [4, 3, 2]}},
        {"id": "ball", "type": "sphere", "material": "m", "to_world": {"translate": [1.5, 0, 0]},
         "emitter": {"type": "area", "radiance": [1, 1, 1]}},
        {"id": "floor", "type": "rectangle", "material": "m", "to_world": {"scale": 5}}],
      "emitters": [{"type": "constant", "radiance": 0.2}]
    })"));
    ASSERT_EQ(scene.emitters.size(), 3u);
    const size_t n = 3001;
    LightBatch b;
    b.resize(n);
    for (size_t k = 0; k < n; ++k) {
        const uint32_t i = uint32_t(k);
        // Mostly near the lights; every 7th reference point on the quad light itself.
        const Vec3f r = k % 7 == 0 ? Vec3f(0.f, 0.f, 2.f)
                                   : Vec3f(4 * sample_1d(4, i, 0, 0) - 2, 4 * sample_1d(4, i, 0, 1) - 2,
                                           3 * sample_1d(4, i, 0, 2) - 0.5f);
        b.rx[k] = r.x();
        b.ry[k] = r.y();
        b.rz[k] = r.z();
        b.u_choice[k] = sample_1d(4, i, 0, 3);
        b.u_pos0[k] = sample_1d(4, i, 0, 4);
        b.u_pos1[k] = sample_1d(4, i, 0, 5);
    }
    scene.lights.sample_batch(scene.emitters, scene.shapes, n, b);
    int valid = 0, kinds[3] = {0, 0, 0};
    for (size_t k = 0; k < n; ++k) {
        const LightSample one = scene.lights.sample(scene.emitters, scene.shapes, Vec3f(b.rx[k], b.ry[k], b.rz[k]),
                                                    b.u_choice[k], Vec2f(b.u_pos0[k], b.u_pos1[k]));
        const LightSample got = b.get(k);
        ASSERT_EQ(got.emitter, one.emitter) << k;
        ASSERT_EQ(got.pdf, one.pdf) << k;
        if (!one.valid()) continue;
        ++valid;
        ++kinds[one.emitter];
        for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(got.p[c], one.p[c]) << k;
            ASSERT_EQ(got.n[c], one.n[c]) << k;
            ASSERT_EQ(got.wi[c], one.wi[c]) << k;
        }
        ASSERT_EQ(got.dist, one.dist) << k;
    }
    EXPECT_GT(valid, int(n) / 3);
    EXPECT_GT(kinds[0], 100);  // every kind of light was exercised
    EXPECT_GT(kinds[1], 100);
    EXPECT_GT(kinds[2], 100);
}

TEST(Camera, BatchRaysEqualOneByOne) {
    // The tracer generates camera rays with generate_rays; they must be generate_ray's floats
    // after filter.sample's offset, for the box and the tent filter, with a scaled, rotated camera.
    Camera cam;
    Eigen::Matrix4f scale = Eigen::Matrix4f::Identity();
    scale.diagonal() << 1.5f, 1.5f, 1.5f, 1.f;
    cam.world_from_camera =
        Transform::look_at(Vec3f(1, 2, 3), Vec3f(0, 0.5f, -1), Vec3f(0.2f, 1, 0)) * Transform(scale);
    cam.width = 37;
    cam.height = 23;
    cam.fov = 52.f;
    for (PixelFilter::Type type : {PixelFilter::Type::Box, PixelFilter::Type::Tent}) {
        cam.filter.type = type;
        cam.filter.radius = type == PixelFilter::Type::Tent ? 1.f : 0.5f;
        const size_t n = 1003;
        std::vector<float> px(n), py(n), u0(n), u1(n), o[8];
        for (auto& a : o) a.resize(n);
        for (size_t k = 0; k < n; ++k) {
            px[k] = float(k % 37);
            py[k] = float(k % 23);
            u0[k] = k == 0 ? 0.5f : sample_1d(6, uint32_t(k), 0, 0);
            u1[k] = k == 0 ? 0.f : sample_1d(6, uint32_t(k), 0, 1);
        }
        const Vec2f th = cam.tan_half_fov();
        cam.generate_rays(
            n, px.data(), py.data(), u0.data(), u1.data(), th,
            {o[0].data(), o[1].data(), o[2].data(), o[3].data(), o[4].data(), o[5].data(), o[6].data(), o[7].data()});
        for (size_t k = 0; k < n; ++k) {
            const Vec2f off = cam.filter.sample(Vec2f(u0[k], u1[k]));
            const Ray r = cam.generate_ray(Vec2f(px[k] + 0.5f + off.x(), py[k] + 0.5f + off.y()), th);
            for (int c = 0; c < 3; ++c) {
                ASSERT_EQ(o[c][k], r.o[c]) << k;
                ASSERT_EQ(o[3 + c][k], r.d[c]) << k;
            }
            ASSERT_EQ(o[6][k], r.tmin) << k;
            ASSERT_EQ(o[7][k], r.tmax) << k;
        }
    }
}

TEST(Camera, CentreRayFollowsLookAtAndFovAxis) {
    Camera cam;
    cam.world_from_camera = Transform::look_at(Vec3f(0, 0, 0), Vec3f(0, 0, 5), Vec3f(0, 1, 0));
    cam.width = 200;
    cam.height = 100;
    cam.fov = 90.f;
    cam.fov_axis = FovAxis::X;
    Ray r = cam.generate_ray(Vec2f(100, 50));
    EXPECT_NEAR((r.d - Vec3f(0, 0, 1)).norm(), 0.f, 1e-6f);
    // Left edge of the image points to +x in camera space (Mitsuba): 45 degrees for fov 90 along x.
    Ray left = cam.generate_ray(Vec2f(0, 50));
    EXPECT_NEAR(left.d.x(), std::sqrt(0.5f), 1e-5f);
    EXPECT_NEAR(left.d.z(), std::sqrt(0.5f), 1e-5f);
    // Top edge: +y, with the vertical half-angle atan(tan(45)/aspect).
    Ray top = cam.generate_ray(Vec2f(100, 0));
    EXPECT_NEAR(std::atan2(top.d.y(), top.d.z()), std::atan(0.5f), 1e-5f);
    cam.fov_axis = FovAxis::Smaller;  // smaller = y here
    top = cam.generate_ray(Vec2f(100, 0));
    EXPECT_NEAR(std::atan2(top.d.y(), top.d.z()), kPi / 4, 1e-5f);
}

TEST(Camera, TentFilterSamplesTriangleDensity) {
    PixelFilter f{PixelFilter::Type::Tent, 1.f};
    // Mean |x| of a unit tent is 1/3; box of radius 0.5 gives 1/4.
    double s = 0;
    const int n = 100000;
    for (int i = 0; i < n; ++i) s += std::abs(f.sample(Vec2f(sample_1d(5, i, 0, 0), 0.5f)).x());
    EXPECT_NEAR(s / n, 1.0 / 3.0, 0.005);
}
