// Mitsuba 3 XML loader: parameters, transforms, properties, plugins, and errors that name the
// file, XML line and offending plugin (textures and the ../shared scenes: test_mitsuba_xml_scenes.cpp).
#include "core/error.h"
#include "core/image_io.h"
#include "core/scene_loader.h"
#include "mitsuba_xml_fixtures.h"
#include "test_util.h"
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <regex>
#include <sstream>

using namespace lpt;

using namespace lpt::test::mitsuba;

TEST(MitsubaXml, DefaultsSubstitutionAndOverride) {
    std::string xml = R"(<scene version="3.0.0">
  <default name="integrator" value="path"/>
  <default name="spp" value="7"/>
  <default name="res" value="20"/>
  <default name="max_depth" value="3"/>
  <integrator type='$integrator'><integer name="max_depth" value="$max_depth"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0,  0,  -3" target="0, 0, 0" up    ="0,  1,  0"/></transform>
    <sampler type="multijitter"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/><rfilter type="tent"/></film>
  </sensor>
  <shape type="rectangle"/>
</scene>)";
    Scene s = load_xml("defaults.xml", xml);
    EXPECT_EQ(s.integrator.spp, 7);
    EXPECT_EQ(s.integrator.max_depth, 3);
    EXPECT_EQ(s.camera.width, 20);
    EXPECT_EQ(s.camera.height, 20);
    EXPECT_EQ(s.camera.filter.type, PixelFilter::Type::Tent);
    EXPECT_FLOAT_EQ(s.camera.filter.radius, 1.f);

    Scene o = load_xml("defaults.xml", xml, {{"res", "33"}, {"max_depth", "-1"}});
    EXPECT_EQ(o.camera.width, 33);
    EXPECT_EQ(o.integrator.max_depth, -1);
    EXPECT_EQ(o.integrator.spp, 7);
    // A define the scene neither declares nor references (a typo, a JSON-style path) is an error.
    for (const char* name : {"unused", "integrator.max_depth"}) {
        try {
            load_xml("defaults.xml", xml, {{name, "1"}});
            ADD_FAILURE() << "-D " << name << " loaded";
        } catch (const SceneError& e) {
            expect_has(e.what(), "defaults.xml");
            expect_has(e.what(), std::string("-D ") + name);
        }
    }
}

TEST(MitsubaXml, MitsubaDefaultsWhenUnset) {
    Scene s = load_xml("bare.xml", scene_xml(kQuad));
    EXPECT_EQ(s.integrator.max_depth, -1);
    EXPECT_EQ(s.integrator.rr_depth, 5);
    EXPECT_EQ(s.integrator.spp, 4);
    EXPECT_EQ(s.camera.fov_axis, FovAxis::X);
    EXPECT_EQ(s.camera.filter.type, PixelFilter::Type::Box);
    EXPECT_FLOAT_EQ(s.camera.filter.radius, 0.5f);
    // A shape without a BSDF gets Mitsuba's default diffuse 0.5.
    ASSERT_EQ(s.materials.size(), 1u);
    EXPECT_EQ(s.materials[0].type, "diffuse");
    EXPECT_TRUE(s.materials[0].get_rgb("reflectance").isApprox(Eigen::Array3f::Constant(0.5f)));
}

TEST(MitsubaXml, EveryTransformKind) {
    auto check = [](const std::string& ops, const Transform& expected) {
        Scene s = load_xml("xf.xml", scene_xml(R"(<shape type="rectangle"><transform name="to_world">)" + ops +
                                               "</transform></shape>"));
        TriangleMesh canonical = make_rectangle();
        ASSERT_EQ(s.shapes[0].mesh.positions.size(), canonical.positions.size());
        for (size_t i = 0; i < canonical.positions.size(); ++i)
            expect_near(s.shapes[0].mesh.positions[i], expected.point(canonical.positions[i]), 1e-4f);
    };
    check(R"(<translate x="1" y="-2" z="3"/>)", Transform::translate(Vec3f(1, -2, 3)));
    check(R"(<translate value="1, -2,3"/>)", Transform::translate(Vec3f(1, -2, 3)));
    check(R"(<translate y="2"/>)", Transform::translate(Vec3f(0, 2, 0)));
    check(R"(<scale value="2.5"/>)", Transform::scale(Vec3f::Constant(2.5f)));
    check(R"(<scale value="1 2 3"/>)", Transform::scale(Vec3f(1, 2, 3)));
    check(R"(<scale x="2" z="4"/>)", Transform::scale(Vec3f(2, 1, 4)));
    check(R"(<rotate y="1" angle="-5"/>)", Transform::rotate(Vec3f(0, 1, 0), -5.f));
    check(R"(<rotate axis="1, 1, 0" angle="30"/>)", Transform::rotate(Vec3f(1, 1, 0), 30.f));
    check(R"(<lookat origin="1, 2, 3" target="0, 0, 0" up="0, 1, 0"/>)",
          Transform::look_at(Vec3f(1, 2, 3), Vec3f::Zero(), Vec3f(0, 1, 0)));
    Eigen::Matrix4f m;
    m << 1, 0, 0, 4, 0, 0, -1, 5, 0, 2, -2.34659e-005f, 6, 0, 0, 0, 1;
    check(R"(<matrix value="1 0 0 4  0 0 -1 5
                               0 2 -2.34659e-005 6  0 0 0 1"/>)",
          Transform(m));
    // Each later operation left-multiplies: scale, then translate, then rotate = R T S.
    check(R"(<scale value="2"/><translate x="1" y="2" z="3"/><rotate x="1" angle="90"/>)",
          Transform::rotate(Vec3f(1, 0, 0), 90.f) * Transform::translate(Vec3f(1, 2, 3)) *
              Transform::scale(Vec3f::Constant(2.f)));

    // The sensor's to_world is the camera transform as is (same frame convention).
    Scene s = load_xml("cam.xml", scene_xml(kQuad));
    EXPECT_TRUE(
        s.camera.world_from_camera.m.isApprox(Transform::look_at(Vec3f(0, 0, -3), Vec3f::Zero(), Vec3f(0, 1, 0)).m));
    EXPECT_FLOAT_EQ(s.camera.fov, 40.f);
    EXPECT_EQ(s.camera.width, 16);
    EXPECT_EQ(s.camera.height, 12);
}

TEST(MitsubaXml, RgbValuesAndBroadcast) {
    Scene s = load_xml("rgb.xml", scene_xml(R"(
  <bsdf type="diffuse" id="a"><rgb name="reflectance" value="0.25"/></bsdf>
  <bsdf type="diffuse" id="b"><rgb name="reflectance" value=" 0.1,0.2   0.3 "/></bsdf>
  <shape type="rectangle" id="qa"><ref id="a"/></shape>
  <shape type="rectangle" id="qb"><ref id="b"/></shape>)"));
    EXPECT_TRUE(s.materials[s.shapes[0].material].get_rgb("reflectance").isApprox(Eigen::Array3f::Constant(0.25f)));
    EXPECT_TRUE(s.materials[s.shapes[1].material].get_rgb("reflectance").isApprox(Eigen::Array3f(0.1f, 0.2f, 0.3f)));
}

TEST(MitsubaXml, RefsNestedAndTwosidedBsdfs) {
    Scene s = load_xml("bsdfs.xml", scene_xml(R"(
  <bsdf type="twosided" id="white">
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf>
  </bsdf>
  <bsdf type="roughconductor" id="metal">
    <float name="alpha" value="0.25"/><string name="distribution" value="beckmann"/>
    <boolean name="sample_visible" value="false"/>
    <rgb name="eta" value="2.8656, 2.11918, 1.94008"/><rgb name="k" value="3.03233, 2.05611, 1.61629"/>
  </bsdf>
  <shape type="rectangle" id="a"><ref id="white"/></shape>
  <shape type="rectangle" id="b"><ref id="white"/></shape>
  <shape type="cube" id="c"><ref id="metal"/></shape>
  <shape type="rectangle" id="d">
    <bsdf type="dielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>
  </shape>)"));
    ASSERT_EQ(s.shapes.size(), 4u);
    EXPECT_EQ(s.shapes[0].material, s.shapes[1].material);  // one material per referenced id
    const Props& white = s.materials[s.shapes[0].material];
    EXPECT_EQ(white.type, "twosided");
    auto inner = white.get_child("bsdf");
    ASSERT_TRUE(inner);
    EXPECT_EQ(inner->type, "diffuse");
    EXPECT_TRUE(inner->get_rgb("reflectance").isApprox(Eigen::Array3f(0.7f, 0.6f, 0.5f)));
    const Props& metal = s.materials[s.shapes[2].material];
    EXPECT_EQ(metal.type, "roughconductor");
    EXPECT_EQ(metal.get_string("distribution"), "beckmann");
    EXPECT_FLOAT_EQ(metal.get_float("alpha"), 0.25f);
    EXPECT_FALSE(metal.get_bool("sample_visible", true));  // Mitsuba's sampling switch loads (ignored)
    const Props& glass = s.materials[s.shapes[3].material];
    EXPECT_EQ(glass.type, "dielectric");
    EXPECT_FLOAT_EQ(glass.get_float("int_ior"), 1.5f);
    EXPECT_EQ(glass.file, s.file);
}

TEST(MitsubaXml, AnalyticShapesAndUnnamedIds) {
    Scene s = load_xml("shapes.xml", scene_xml(R"(
  <shape type="rectangle"><transform name="to_world"><scale value="2"/></transform></shape>
  <shape type="cube" id="shape_0"/>
  <shape type="sphere" id="ball">
    <point name="center" x="-3" y="4" z="0"/><float name="radius" value="0.4"/>
  </shape>
  <shape type="sphere" id="ball2">
    <transform name="to_world"><scale value="0.5"/><translate x="1" y="0" z="0"/></transform>
  </shape>
  <shape type="rectangle"><boolean name="flip_normals" value="true"/></shape>)"));
    ASSERT_EQ(s.shapes.size(), 5u);
    EXPECT_NEAR(s.shapes[0].area(), 16.f, 1e-4f);
    EXPECT_EQ(s.shapes[0].id, "shape_0_2");  // "shape_0" is taken by the cube
    EXPECT_NEAR(s.shapes[1].area(), 24.f, 1e-4f);
    for (const Vec3f& p : s.shapes[2].mesh.positions) EXPECT_NEAR((p - Vec3f(-3, 4, 0)).norm(), 0.4f, 1e-5f);
    for (const Vec3f& p : s.shapes[3].mesh.positions) EXPECT_NEAR((p - Vec3f(1, 0, 0)).norm(), 0.5f, 1e-5f);
    EXPECT_EQ(s.shapes[4].id, "shape_4");
    // flip_normals: the rectangle now faces -z.
    EXPECT_LT(s.shapes[4].sample_position(Eigen::Vector3f(0.5f, 0.5f, 0.5f)).n.z(), -0.99f);
}

TEST(MitsubaXml, AreaAndConstantEmitters) {
    Scene s = load_xml("emit.xml", scene_xml(R"(
  <shape type="rectangle" id="floor"/>
  <emitter type="constant" id="sky"><rgb name="radiance" value="5.0"/></emitter>
  <shape type="rectangle" id="light">
    <transform name="to_world"><translate z="1"/></transform>
    <emitter type="area"><rgb name="radiance" value="17, 12, 4"/></emitter>
  </shape>)"));
    ASSERT_EQ(s.emitters.size(), 2u);
    ASSERT_EQ(s.environment, 0);
    EXPECT_EQ(s.emitters[0].kind, EmitterKind::Constant);
    EXPECT_TRUE(s.emitters[0].radiance_rgb.isApprox(Eigen::Array3f::Constant(5.f)));
    const Emitter& area = s.emitters[1];
    EXPECT_EQ(area.kind, EmitterKind::Area);
    EXPECT_EQ(area.shape, s.find_shape("light"));
    EXPECT_EQ(s.shapes[area.shape].emitter, 1);
    EXPECT_TRUE(area.radiance_rgb.isApprox(Eigen::Array3f(17, 12, 4)));
    EXPECT_EQ(area.props.type, "area");
}

TEST(MitsubaXml, MediaAreSkipped) {
    Scene s = load_xml("medium.xml", scene_xml(R"(
  <medium type="homogeneous" id="interior"><rgb name="albedo" value="0.9"/></medium>
  <shape type="cube"><ref name="interior" id="interior"/></shape>)"));
    EXPECT_EQ(s.shapes.size(), 1u);
}

TEST(MitsubaXml, MalformedXmlNamesLine) {
    std::string xml = "<scene version=\"3.0.0\">\n  <shape type=\"cube\">\n  </shap>\n</scene>\n";
    std::string err = load_error("malformed.xml", xml);
    expect_has(err, "malformed XML");
    expect_has(err, at_line("malformed.xml", 3));
}

TEST(MitsubaXml, UnknownPluginNamesTypeAndLine) {
    struct Case {
        const char* element;
        const char* type;
    };
    for (Case c : {Case{R"(<shape type="torus"/>)", "torus"}, Case{R"(<bsdf type="velvet" id="v"/>)", "velvet"},
                   Case{R"(<emitter type="point"/>)", "point"}, Case{R"(<integrator type="volpath"/>)", "volpath"},
                   Case{R"(<texture type="checkerboard" id="t"/>)", "checkerboard"}}) {
        std::string xml = scene_xml(std::string("\n\n") + c.element + "\n" + kQuad);
        std::string err = load_error("unknown.xml", xml);
        expect_has(err, at_line("unknown.xml", line_of(xml, c.element)));
        expect_has(err, std::string("'") + c.type + "'");
    }
    std::string sensor = kSensor;
    sensor.replace(sensor.find("\"box\""), 5, "\"lanczos\"");
    std::string xml = scene_xml(kQuad, sensor);
    std::string err = load_error("rfilter.xml", xml);
    expect_has(err, at_line("rfilter.xml", line_of(xml, "lanczos")));
    expect_has(err, "'lanczos'");
}

// A scene holds one camera and one integrator; the second is an error at its own line.
TEST(MitsubaXml, SecondSensorOrIntegratorNamesItsLine) {
    const std::string integrator = "<integrator type=\"path\"/>";
    std::string xml = scene_xml("\n" + integrator + "\n" + integrator + "\n" + kQuad);
    std::string err = load_error("integrators.xml", xml);
    expect_has(err, at_line("integrators.xml", line_of(xml, integrator) + 1));
    expect_has(err, "only one <integrator> is supported");
    xml = scene_xml(kQuad, kSensor + kSensor);
    err = load_error("sensors.xml", xml);
    const int second = line_of(xml, "<sensor") + int(std::count(kSensor.begin(), kSensor.end(), '\n'));
    expect_has(err, at_line("sensors.xml", second));
    expect_has(err, "only one <sensor> is supported");
}

TEST(MitsubaXml, UnsupportedFeaturesAreErrors) {
    auto check = [](const std::string& name, const std::string& xml, const std::string& needle,
                    const std::string& msg) {
        std::string err = load_error(name, xml);
        expect_has(err, at_line(name, line_of(xml, needle)));
        expect_has(err, msg);
    };
    std::string env = R"(<emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>)";
    check("envmap.xml", scene_xml("\n" + kQuad + "\n" + env), "envmap", "sky.exr: cannot open image file");
    std::string gauss = kSensor;
    gauss.replace(gauss.find("\"box\""), 5, "\"gaussian\"");
    check("gauss.xml", scene_xml(kQuad, gauss), "gaussian", "unsupported, use box or tent");
    std::string diag = kSensor;
    diag.insert(diag.find("<float"), "<string name=\"fov_axis\" value=\"diagonal\"/>\n");
    check("diag.xml", scene_xml(kQuad, diag), "diagonal", "diagonal");
    check("prop.xml", scene_xml("\n<shape type=\"cube\"><float name=\"radius\" value=\"2\"/></shape>"), "radius",
          "does not support property 'radius'");
    check("twoback.xml",
          scene_xml("\n<bsdf type=\"twosided\" id=\"t\"><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\"/></bsdf>\n" +
                    kQuad),
          "twosided", "back-side");
}

TEST(MitsubaXml, ZeroAreaTrianglesAreDroppedAsMitsubaDoes) {
    // Triangle 2 repeats a vertex. Mitsuba drops it; so does our XML loader, while the JSON
    // format rejects it.
    std::string obj =
        test::write_temp_file("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 3\nf 1 3 4\n");
    Scene s = load_xml(
        "degenerate.xml",
        scene_xml("\n<shape type=\"obj\" id=\"m\"><string name=\"filename\" value=\"degenerate.obj\"/></shape>"));
    EXPECT_EQ(s.shapes[0].mesh.triangle_count(), 2u);
    std::string json =
        test::write_temp_file("degenerate.json", R"({"camera": {}, "materials": {"w": {"type": "diffuse"}},
        "shapes": [{"type": "obj", "filename": "degenerate.obj", "material": "w"}]})");
    std::string err;
    try {
        load_scene(json);
    } catch (const SceneError& e) {
        err = e.what();
    }
    expect_has(err, "zero area");
}

TEST(MitsubaXml, UndefinedRefNamesIdAndLine) {
    std::string xml = scene_xml("\n<shape type=\"cube\">\n  <ref id=\"whte\"/>\n</shape>");
    std::string err = load_error("badref.xml", xml);
    expect_has(err, at_line("badref.xml", line_of(xml, "whte")));
    expect_has(err, "'whte'");
    xml = scene_xml("\n<bsdf type=\"diffuse\" id=\"w\"/>\n<bsdf type=\"diffuse\" id=\"w\"/>\n" + kQuad);
    err = load_error("dupid.xml", xml);
    expect_has(err, "duplicate id 'w'");
}

TEST(MitsubaXml, UndefinedParameterNamesIt) {
    std::string xml = scene_xml("\n<shape type=\"sphere\">\n  <float name=\"radius\" value=\"$size\"/>\n</shape>");
    std::string err = load_error("undef.xml", xml);
    expect_has(err, "$size");
    expect_has(err, at_line("undef.xml", line_of(xml, "$size")));
    // A define supplies it, as Mitsuba's -D does.
    Scene s = load_xml("undef.xml", xml, {{"size", "2"}});
    EXPECT_NEAR(s.shapes[0].mesh.positions[0].norm(), 2.f, 1e-5f);
}

TEST(MitsubaXml, BadNumbersNameProperty) {
    std::string xml = scene_xml("\n<shape type=\"sphere\">\n  <float name=\"radius\" value=\"1.5x\"/>\n</shape>");
    std::string err = load_error("badnum.xml", xml);
    expect_has(err, at_line("badnum.xml", line_of(xml, "1.5x")));
    expect_has(err, "radius");
    expect_has(err, "'1.5x'");
    xml = scene_xml("\n<bsdf type=\"diffuse\" id=\"d\">\n  <rgb name=\"reflectance\" value=\"0.5, 0.5\"/>\n</bsdf>\n" +
                    kQuad);
    err = load_error("badrgb.xml", xml);
    expect_has(err, at_line("badrgb.xml", line_of(xml, "0.5, 0.5")));
    expect_has(err, "reflectance");
    std::string sensor = kSensor;
    sensor.replace(sensor.find("\"16\""), 4, "\"16.5\"");
    xml = scene_xml(kQuad, sensor);
    err = load_error("badint.xml", xml);
    expect_has(err, "width");
    expect_has(err, at_line("badint.xml", line_of(xml, "16.5")));
    xml = scene_xml(
        "\n<shape type=\"rectangle\"><transform name=\"to_world\">\n<matrix value=\"1 0 0 0 1 "
        "0\"/></transform></shape>");
    expect_has(load_error("badmat.xml", xml), at_line("badmat.xml", line_of(xml, "<matrix")));
}

TEST(MitsubaXml, OldVersionsAndBadBsdfValuesAreErrors) {
    std::string err = load_error("old.xml", "<scene version=\"0.6.0\">\n<shape type=\"cube\"/></scene>");
    expect_has(err, "0.6.0");
    expect_has(err, "camelCase");
    // BSDF values are validated at load time by the BSDF factory, with the XML line added.
    std::string xml = scene_xml(
        "\n\n<bsdf type=\"roughconductor\" id=\"m\"><float name=\"alpha_u\" value=\"0.1\"/></bsdf>\n" + kQuad);
    err = load_error("alpha.xml", xml);
    expect_has(err, at_line("alpha.xml", line_of(xml, "roughconductor")));
    expect_has(err, "bsdf 'm'");
}

TEST(MitsubaXml, BsdfPropertiesNoReaderAsksForAreErrors) {
    // Mitsuba refuses unreferenced properties too: a typo must not leave the default in place.
    std::string xml =
        scene_xml("\n<bsdf type=\"diffuse\" id=\"d\">\n  <rgb name=\"reflectanse\" value=\"0.2\"/>\n</bsdf>\n" + kQuad);
    std::string err = load_error("typo.xml", xml);
    expect_has(err, at_line("typo.xml", line_of(xml, "<bsdf")));
    expect_has(err, "reflectanse");
    expect_has(err, "it reads reflectance");
    // Inside a twosided BSDF too.
    xml = scene_xml(
        "\n<bsdf type=\"twosided\" id=\"t\"><bsdf type=\"plastic\"><float name=\"int_iro\" value=\"1.5\"/></bsdf>"
        "</bsdf>\n" +
        kQuad);
    expect_has(load_error("nested_typo.xml", xml), "int_iro");
}

TEST(MitsubaXml, NegativeColoursAreErrors) {
    std::string xml = scene_xml(
        "\n<bsdf type=\"conductor\" id=\"c\">\n  <rgb name=\"specular_reflectance\" value=\"1, -1, 1\"/>\n</bsdf>\n" +
        kQuad);
    std::string err = load_error("neg_spec.xml", xml);
    expect_has(err, at_line("neg_spec.xml", line_of(xml, "<bsdf")));
    expect_has(err, "specular_reflectance");
    expect_has(err, ">= 0");
    xml = scene_xml(
        "\n<shape type=\"rectangle\">\n  <emitter type=\"area\"><rgb name=\"radiance\" value=\"-3\"/></emitter>\n"
        "</shape>");
    err = load_error("neg_rad.xml", xml);
    expect_has(err, "radiance");
    expect_has(err, ">= 0");
}
