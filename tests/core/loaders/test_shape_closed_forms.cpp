// Shapes and emitters from Mitsuba XML against closed forms (docs/validation.md (7)-(9)):
// rectangle emitters under non-uniform scale and shear (veach-bidir's two lights), face_normals on
// OBJ meshes, and the smooth normals Mitsuba 3 computes for mesh files that store none.
#include "core/emitter.h"
#include "core/sampler.h"
#include "core/scene_loader.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>
#include <sstream>

using namespace lpt;

namespace {

Scene load_xml(const std::string& name, const std::string& body) {
    const std::string xml = R"(<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/><transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>
)" + body + "\n</scene>\n";
    return load_scene(test::write_temp_file(name, xml));
}

/// Solid angle of the triangle (a, b, c) seen from the origin (Van Oosterom & Strackee 1983).
double triangle_solid_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = std::abs(a.dot(b.cross(c)));
    const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    return 2.0 * std::atan2(num, den);
}

struct RectCase {
    const char* name;
    const char* matrix;  ///< row-major 4x4, as in the XML
};

// veach-bidir's Diffuse_0002 and Diffuse_0003, and a strongly sheared, mirrored-free case.
const RectCase kRects[] = {
    {"veach Diffuse_0002",
     "-1.20536e-008 0.275755 1.20536e-008 -2.48161 0 -6.64767e-009 0.152081 6 0.275754 1.20536e-008 5.2688e-016 2.5894 "
     "0 0 0 1"},
    {"veach Diffuse_0003",
     "-0.0101082 0.067068 0.00138972 -2.69082 -0.0610016 -0.0070995 -0.00842772 5.10417 -0.0282857 -0.00865658 "
     "0.0176788 -3.77057 0 0 0 1"},
    {"sheared", "0.3 0.2 0.1 1 0 0.5 -0.4 2 0 0 2 -1 0 0 0 1"},
};

}  // namespace

TEST(ClosedForm, RectangleEmitterAreaNormalAndPdfUnderScaleAndShear) {
    for (const RectCase& rc : kRects) {
        Scene s =
            load_xml("rect.xml",
                     std::string(R"(<shape type="rectangle" id="light"><transform name="to_world"><matrix value=")") +
                         rc.matrix +
                         R"("/></transform><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>)");
        std::istringstream in(rc.matrix);
        Eigen::Matrix4d m;
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) in >> m(r, c);
        const Eigen::Vector3d c1 = m.block<3, 1>(0, 0), c2 = m.block<3, 1>(0, 1), t = m.block<3, 1>(0, 3);
        const Shape& light = s.shapes[size_t(s.find_shape("light"))];
        // Area of the image of [-1, 1]^2: 4 |M e_x x M e_y|.
        EXPECT_NEAR(light.area(), 4.0 * c1.cross(c2).norm(), 1e-5 * 4.0 * c1.cross(c2).norm()) << rc.name;
        // Normal: the inverse transpose of M applied to +z (Mitsuba's rectangle normal).
        const Eigen::Vector3d n =
            (m.topLeftCorner<3, 3>().inverse().transpose() * Eigen::Vector3d::UnitZ()).normalized();
        const PositionSample ps = light.sample_position(Eigen::Vector3f(0.3f, 0.6f, 0.2f));
        EXPECT_GT(ps.n.cast<double>().dot(n), 1.0 - 1e-6) << rc.name << ": normal " << ps.n.transpose();
        // E[1 / pdf] over light samples = solid angle, from a point on the emitting side.
        const Eigen::Vector3d size(c1.norm() + c2.norm(), 0, 0);
        const Eigen::Vector3d ref = t + 2.5 * size.x() * n + 0.3 * c1;
        const Eigen::Vector3d p00 = t - c1 - c2 - ref, p10 = t + c1 - c2 - ref, p11 = t + c1 + c2 - ref,
                              p01 = t - c1 + c2 - ref;
        const double omega = triangle_solid_angle(p00, p10, p11) + triangle_solid_angle(p00, p11, p01);
        double sum = 0, sum2 = 0;
        const int count = 100000;
        for (int i = 0; i < count; ++i) {
            LightSample ls =
                sample_area_light(light, ref.cast<float>(),
                                  Eigen::Vector3f(sample_1d(3, i, 0, 0), sample_1d(3, i, 0, 1), sample_1d(3, i, 0, 2)));
            ASSERT_TRUE(ls.valid()) << rc.name;
            EXPECT_NEAR(ls.pdf, pdf_area_light(light, ref.cast<float>(), ls.p, ls.n), 1e-4f * ls.pdf);
            sum += 1.0 / ls.pdf;
            sum2 += 1.0 / (double(ls.pdf) * ls.pdf);
        }
        const double mean = sum / count, se = std::sqrt((sum2 / count - mean * mean) / count);
        EXPECT_NEAR(mean, omega, 4 * se + 1e-6 * omega) << rc.name;
    }
}

namespace {

// One triangle whose file normals lean away from its face normal (+z).
const char* kTiltedTriangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0.5 0 1\nvn 0.5 0 1\nvn 0.5 0 1\nf 1//1 2//2 3//3\n";

std::string obj_shape(const std::string& file, bool face_normals) {
    return "<shape type=\"obj\" id=\"m\"><string name=\"filename\" value=\"" + file +
           "\"/><boolean name=\"face_normals\" value=\"" + (face_normals ? "true" : "false") + "\"/></shape>";
}

}  // namespace

TEST(ClosedForm, FaceNormalsReplaceObjVertexNormals) {
    const std::string file = test::write_temp_file("tilted.obj", kTiltedTriangle);
    for (bool face : {false, true}) {
        Scene s = load_xml("tilted.xml", obj_shape(file, face));
        const SurfaceInteraction si = s.shapes[0].interaction(0, 0.2f, 0.3f, 1.f);
        const Vec3f expected = face ? Vec3f(0, 0, 1) : Vec3f(0.5f, 0, 1).normalized();
        EXPECT_LT((si.sh.n - expected).norm(), 1e-6f) << "face_normals " << face << ": " << si.sh.n.transpose();
        EXPECT_LT((si.ng - Vec3f(0, 0, 1)).norm(), 1e-6f);
        EXPECT_EQ(s.shapes[0].flat(), face);
    }
}

TEST(ClosedForm, ObjWithoutNormalsIsSmoothShadedAsMitsuba3) {
    // A roof: two triangles folded 90 degrees along the shared edge (0,0,0)-(0,1,0). At a shared
    // vertex each face contributes its unit normal times its interior angle there.
    const std::string roof =
        test::write_temp_file("roof.obj", "v 0 0 0\nv 0 1 0\nv -1 0 -1\nv 1 0 -1\nf 1 2 3\nf 1 4 2\n");
    Scene s = load_xml("roof.xml", obj_shape(roof, false));
    const TriangleMesh& m = s.shapes[0].mesh;
    ASSERT_EQ(m.normals.size(), 4u);
    const Vec3f n1 = (m.positions[1] - m.positions[0]).cross(m.positions[2] - m.positions[0]).normalized();
    const Vec3f n2 = (m.positions[3] - m.positions[0]).cross(m.positions[1] - m.positions[0]).normalized();
    auto angle = [&](int at, int a, int b) {
        const Vec3f u = (m.positions[a] - m.positions[at]).normalized(),
                    v = (m.positions[b] - m.positions[at]).normalized();
        return std::acos(std::clamp(u.dot(v), -1.f, 1.f));
    };
    const Vec3f expect0 = (angle(0, 1, 2) * n1 + angle(0, 3, 1) * n2).normalized();
    EXPECT_LT((m.normals[0] - expect0).norm(), 1e-5f) << m.normals[0].transpose();
    EXPECT_LT((m.normals[2] - n1).norm(), 1e-6f);  // used by one face only
    EXPECT_FALSE(s.shapes[0].flat());
    // face_normals keeps it faceted; a planar quad without normals stays flat (same surface).
    EXPECT_TRUE(load_xml("roof_flat.xml", obj_shape(roof, true)).shapes[0].flat());
    const std::string quad = test::write_temp_file("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    EXPECT_TRUE(load_xml("quad.xml", obj_shape(quad, false)).shapes[0].flat());
}
