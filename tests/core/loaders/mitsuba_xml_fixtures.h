// Helpers of the Mitsuba 3 XML loader tests: a scene around a body, loading from a temporary
// file, and checks that errors name the file, the line and the part.
#pragma once
#include "core/error.h"
#include "core/scene_loader.h"
#include "test_util.h"
#include <algorithm>
#include <gtest/gtest.h>
#include <map>
#include <string>

namespace lpt::test::mitsuba {

inline const std::string kSensor = R"(
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 0, -3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/><rfilter type="box"/></film>
  </sensor>
)";

inline std::string scene_xml(const std::string& body, const std::string& sensor = kSensor) {
    return "<scene version=\"3.0.0\">" + sensor + body + "\n</scene>\n";
}

inline Scene load_xml(const std::string& name, const std::string& xml,
                      const std::map<std::string, std::string>& defines = {}) {
    return load_scene(test::write_temp_file(name, xml), defines);
}

/// The SceneError message of loading `xml` ("" if it loaded).
inline std::string load_error(const std::string& name, const std::string& xml) {
    try {
        load_xml(name, xml);
    } catch (const SceneError& e) {
        return e.what();
    }
    return "";
}

/// 1-based line of the first occurrence of `needle` in `text`.
inline int line_of(const std::string& text, const std::string& needle) {
    size_t pos = text.find(needle);
    EXPECT_NE(pos, std::string::npos) << needle;
    return 1 + int(std::count(text.begin(), text.begin() + pos, '\n'));
}

/// "file.xml:<line>:" as SceneError formats it.
inline std::string at_line(const std::string& file, int line) { return file + ":" + std::to_string(line) + ":"; }

inline void expect_has(const std::string& err, const std::string& part) {
    EXPECT_NE(err.find(part), std::string::npos) << "'" << part << "' not in: " << err;
}

inline void expect_near(const Vec3f& a, const Vec3f& b, float tol = 1e-5f) {
    EXPECT_LT((a - b).norm(), tol) << a.transpose() << " vs " << b.transpose();
}

const std::string kQuad = R"(<shape type="rectangle" id="q"/>)";

}  // namespace lpt::test::mitsuba
