// max_depth read from Mitsuba XML means what it means in Mitsuba 3: the longest path in
// segments, 1 = emitters seen directly, 2 = direct lighting (docs/validation.md (10)). Camera
// inside a closed one-sided emitting sphere of albedo a: radiance sum_{k < max_depth} a^k.
#include "core/scene_loader.h"
#include "integrators/path.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace lpt;

TEST(PathTracer, XmlMaxDepthIsMitsubaSegmentCount) {
    const float a = 0.6f;
    for (int d : {1, 2, 3, 7}) {
        const std::string scene = R"(<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value=")" +
                                  std::to_string(d) + R"("/><integer name="rr_depth" value="100"/></integrator>
  <sensor type="perspective"><float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
  <shape type="sphere"><boolean name="flip_normals" value="true"/>
    <bsdf type="diffuse"><rgb name="reflectance" value=")" +
                                  std::to_string(a) + R"("/></bsdf>
    <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
</scene>)";
        Scene s = load_scene(test::write_temp_file("depth.xml", scene));
        ASSERT_EQ(s.integrator.max_depth, d);
        auto spectra = SceneSpectra<3>::from_description(s);
        RenderOptions opt = RenderOptions::from_scene(s);
        opt.spp = 256;
        const auto img = render_path<3>(s, spectra, opt).develop();
        double sum = 0, sum2 = 0;
        for (size_t i = 0; i < img.size(); i += 3) sum += img[i], sum2 += double(img[i]) * img[i];
        const double n = double(img.size() / 3), mean = sum / n,
                     se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / (n - 1));
        const double expected = (1.0 - std::pow(a, d)) / (1.0 - a);
        // 1e-3 relative for float round-off along long paths (as the JSON furnace test); one
        // segment more or less changes the value by a^(d-1) >= 4.7 %.
        EXPECT_NEAR(mean, expected, 4 * se + 1e-3 * expected) << "max_depth " << d;
    }
}
