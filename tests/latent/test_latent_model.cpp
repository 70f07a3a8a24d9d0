// LatentModel: one BSDF per shape without touching the scene it reads.
#include "core/scene_loader.h"
#include "latent/latent_model.h"
#include <gtest/gtest.h>

using namespace lpt;

namespace {

Scene cornell_box() { return load_scene(std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json"); }

/// Two shapes of `scene` that share one material in the scene file.
std::pair<int, int> shapes_sharing_a_material(const Scene& scene) {
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        for (size_t j = i + 1; j < scene.shapes.size(); ++j)
            if (scene.shapes[i].material == scene.shapes[j].material) return {int(i), int(j)};
    return {-1, -1};
}

}  // namespace

TEST(LatentModel, LeavesTheScenesMaterialsAsTheyWere) {
    const Scene scene = cornell_box();
    std::vector<int> before;
    for (const Shape& s : scene.shapes) before.push_back(s.material);
    const size_t materials = scene.materials.size();
    LatentModel model(scene, Parameterisation::Code, 3);
    EXPECT_EQ(scene.materials.size(), materials);
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        EXPECT_EQ(scene.shapes[i].material, before[i]) << scene.shapes[i].id;
}

TEST(LatentModel, ShapesSharingAMaterialLearnTheirOwnReflectance) {
    const Scene scene = cornell_box();
    const auto [a, b] = shapes_sharing_a_material(scene);
    ASSERT_GE(a, 0) << "the bundled box should have two shapes with one material";
    LatentModel model(scene, Parameterisation::Code, 3);
    ASSERT_FALSE(model.slots(a).bsdf.empty());
    const int slice_a = model.slots(a).bsdf.front().second;
    std::vector<float> v(kLatentChannels, 0.25f);
    model.params().set_value(slice_a, v.data());
    model.sync();
    const BSDFContext ctx{};
    const Vec3f up(0, 0, 1), wo = Vec3f(0.3f, 0.1f, 1.f).normalized();
    const Latent fa = model.spectra().bsdf_of(scene, a).eval(ctx, up, wo);
    const Latent fb = model.spectra().bsdf_of(scene, b).eval(ctx, up, wo);
    EXPECT_NEAR(fa[0], 0.25f * wo.z() / 3.14159265f, 1e-5f);
    EXPECT_GT((fa - fb).cwiseAbs().maxCoeff(), 1e-3f) << "the shapes share one BSDF";
}
