// The samplers through the whole tracer (docs/sampling.md): a flat-lit plane whose exact value is
// known, so the error image is pure sampling error. It must have no spatial pattern (pixels draw
// from unrelated scrambles), and the Sobol sampler must reach less error than the independent one
// at the same spp. The XML <sampler> types map to the nearest sampler we have.
#include "core/scene_loader.h"
#include "integrators/path.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>

using namespace lpt;

namespace {

/// A twosided diffuse plane of albedo 0.5 filling the view under a constant environment of
/// radiance 1, at max_depth 2: every pixel's expected value is exactly 0.5.
std::string flat_plane_xml(const std::string& sampler_type) {
    return R"(<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, -3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type=")" +
           sampler_type + R"("><integer name="sample_count" value="4"/></sampler>
    <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/><rfilter type="box"/></film></sensor>
  <shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>
    <bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></bsdf></shape>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>)";
}

/// Error image (green channel minus the exact 0.5) of a render of the flat plane.
std::vector<double> error_image(const Scene& scene, SamplerKind sampler, int spp, uint64_t seed) {
    RenderOptions opt = RenderOptions::from_scene(scene);
    opt.sampler = sampler;
    opt.spp = spp;
    opt.seed = seed;
    const auto img = render_path<3>(scene, SceneSpectra<3>::from_description(scene), opt).develop();
    std::vector<double> e(img.size() / 3);
    for (size_t i = 0; i < e.size(); ++i) e[i] = double(img[i * 3 + 1]) - 0.5;
    return e;
}

/// Normalised autocorrelation of a w x w error image at lag (dx, dy).
double autocorrelation(const std::vector<double>& e, int w, int dx, int dy) {
    double mean = 0;
    for (double v : e) mean += v / double(e.size());
    double num = 0, den = 0;
    for (int y = 0; y < w; ++y)
        for (int x = 0; x < w; ++x) {
            const double a = e[size_t(y * w + x)] - mean;
            den += a * a;
            if (x + dx < w && y + dy < w) num += a * (e[size_t((y + dy) * w + x + dx)] - mean);
        }
    return num / den;
}

}  // namespace

TEST(Samplers, XmlSamplerTypesMapToTheNearestWeHave) {
    for (const char* t : {"stratified", "multijitter", "ldsampler", "orthogonal"})
        EXPECT_EQ(load_scene(test::write_temp_file("plane.xml", flat_plane_xml(t))).integrator.sampler,
                  SamplerKind::Sobol)
            << t;
    EXPECT_EQ(load_scene(test::write_temp_file("plane.xml", flat_plane_xml("independent"))).integrator.sampler,
              SamplerKind::Independent);
    EXPECT_THROW(load_scene(test::write_temp_file("plane.xml", flat_plane_xml("halton"))), std::exception);
}

TEST(Samplers, FlatLitPlaneErrorImageHasNoPattern) {
    Scene scene = load_scene(test::write_temp_file("plane.xml", flat_plane_xml("ldsampler")));
    for (SamplerKind sampler : {SamplerKind::Sobol, SamplerKind::Independent}) {
        const auto e = error_image(scene, sampler, 4, 3);
        double mean = 0, var = 0;
        for (double v : e) mean += v / double(e.size());
        for (double v : e) var += (v - mean) * (v - mean) / double(e.size() - 1);
        EXPECT_NEAR(mean, 0.0, 4.0 * std::sqrt(var / double(e.size()))) << sampler_name(sampler) << ": unbiased";
        // 4096 pixels: an autocorrelation of pure noise has sd ~ 1/64; a shared scramble or a
        // pixel-periodic pattern would put it near 1 at some lag.
        for (auto [dx, dy] : {std::pair{1, 0}, {0, 1}, {1, 1}, {2, 0}, {0, 2}, {4, 0}, {8, 0}, {0, 8}, {16, 16}})
            EXPECT_LT(std::abs(autocorrelation(e, 64, dx, dy)), 5.0 / 64.0)
                << sampler_name(sampler) << " lag " << dx << "," << dy;
    }
}

TEST(Samplers, SobolHasLessErrorThanIndependentOnTheFlatPlane) {
    Scene scene = load_scene(test::write_temp_file("plane.xml", flat_plane_xml("ldsampler")));
    for (int spp : {4, 16, 64}) {
        double mse[2] = {0, 0};
        for (SamplerKind sampler : {SamplerKind::Sobol, SamplerKind::Independent})
            for (double v : error_image(scene, sampler, spp, 7)) mse[int(sampler == SamplerKind::Independent)] += v * v;
        // The issue's target is >= 1.5x fewer spp for the same noise: at N^-1 vs N^-1/2 variance
        // decay that is a variance ratio of at least 1.5 at these spp.
        EXPECT_LT(mse[0] * 1.5, mse[1]) << spp << " spp: Sobol MSE " << mse[0] << ", independent " << mse[1];
    }
}
