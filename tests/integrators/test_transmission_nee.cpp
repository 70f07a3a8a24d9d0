// Next-event estimation through a non-delta transmissive surface (rough dielectric): the light
// lies on the far side of the surface, which is not an attached shadow. MIS, NEE alone and BSDF
// sampling alone must agree (docs/validation.md).
#include "core/scene_loader.h"
#include "integrators/path.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace lpt;

namespace {

/// Camera at the origin looking up +z through a rough glass interface at z = 1 (exterior below)
/// at a one-sided light at z = 1.5 facing down: every path reaches the light by transmission.
Scene rough_glass_scene() {
    const std::string xml = R"(<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/><rfilter type="box"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale value="10"/><rotate x="1" angle="180"/><translate z="1"/></transform>
    <bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.6"/><rotate x="1" angle="180"/><translate z="1.5"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter>
  </shape>
</scene>
)";
    return load_scene(test::write_temp_file("rough_glass.xml", xml));
}

std::vector<float> render(const Scene& scene, LightStrategy s, int spp) {
    auto spectra = SceneSpectra<3>::from_description(scene);
    RenderOptions opt = RenderOptions::from_scene(scene);
    opt.spp = spp;
    opt.seed = 5;
    opt.strategy = s;
    return render_path<3>(scene, spectra, opt).develop();
}

}  // namespace

TEST(PathTracer, NeeThroughRoughDielectricAgreesWithBsdfSampling) {
    Scene scene = rough_glass_scene();
    const int spp = 256;
    const auto bsdf = render(scene, LightStrategy::Bsdf, spp);
    for (LightStrategy s : {LightStrategy::Mis, LightStrategy::Nee}) {
        const auto img = render(scene, s, spp);
        // Paired per-pixel differences: pixels are independent, so their spread is the standard
        // error of the mean difference.
        double sum = 0, sum2 = 0, ref = 0;
        const size_t n = img.size();
        for (size_t i = 0; i < n; ++i) {
            double d = double(img[i]) - bsdf[i];
            sum += d;
            sum2 += d * d;
            ref += bsdf[i];
        }
        const double mean = sum / double(n), se = std::sqrt((sum2 / double(n) - mean * mean) / double(n - 1));
        EXPECT_GT(ref / double(n), 0.05) << "the light must be seen through the glass";
        EXPECT_LT(std::abs(mean), 4 * se) << "strategy " << int(s) << ": mean difference " << mean << " (relative "
                                          << mean / (ref / double(n)) << "), standard error " << se;
    }
}
