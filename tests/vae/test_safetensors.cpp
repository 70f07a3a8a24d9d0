// safetensors reader: conversions, every kind of malformed file, and the shared TAESD3 weights
// against the shapes and value ranges listed in ../shared/models/taesd3/taesd3_keys.txt.
#include "vae/safetensors.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>

using namespace lpt;

namespace {

std::string file_bytes(const std::string& header, const std::string& data) {
    std::string out(8, '\0');
    uint64_t n = header.size();
    for (int i = 0; i < 8; ++i) out[i] = char((n >> (8 * i)) & 0xff);
    return out + header + data;
}

std::string u16s(std::initializer_list<uint16_t> v) {
    std::string s;
    for (uint16_t x : v) s += char(x & 0xff), s += char(x >> 8);
    return s;
}

std::string parse_error(const std::string& bytes) {
    return test::runtime_error_of([&] { SafeTensors::parse(bytes, "weights.safetensors"); });
}

}  // namespace

TEST(SafeTensors, ReadsAndConvertsEveryDtype) {
    float f32[2] = {1.5f, -2.25f};
    std::string data =
        u16s({0x3f80, 0xc040}) + u16s({0x3c00, 0x0001, 0x7c00}) + std::string(reinterpret_cast<char*>(f32), 8);
    std::string header = R"({"__metadata__": {"format": "pt"},
        "b": {"dtype": "BF16", "shape": [2], "data_offsets": [0, 4]},
        "h": {"dtype": "F16", "shape": [3, 1], "data_offsets": [4, 10]},
        "f": {"dtype": "F32", "shape": [1, 2], "data_offsets": [10, 18]}})";
    SafeTensors st = SafeTensors::parse(file_bytes(header, data), "mem");
    EXPECT_EQ(st.tensors().size(), 3u);
    EXPECT_EQ(st.metadata().at("format"), "pt");
    EXPECT_EQ(st.to_float("b"), (std::vector<float>{1.f, -3.f}));
    auto h = st.to_float("h", {3, 1});
    EXPECT_EQ(h[0], 1.f);
    EXPECT_EQ(h[1], std::ldexp(1.f, -24));  // smallest f16 subnormal
    EXPECT_TRUE(std::isinf(h[2]));
    EXPECT_EQ(st.to_float("f"), (std::vector<float>{1.5f, -2.25f}));
    test::expect_error_naming([&] { st.to_float("f", {2, 1}); }, {"has shape [1, 2], expected [2, 1]"});
    EXPECT_THROW(st.to_float("missing"), std::runtime_error);
}

TEST(SafeTensors, MalformedFilesAreClearErrors) {
    const std::string ok_header = R"({"w": {"dtype": "F32", "shape": [2], "data_offsets": [0, 8]}})";
    const std::string data(8, '\0');
    ASSERT_EQ(parse_error(file_bytes(ok_header, data)), "");
    auto expect = [](const std::string& err, const std::string& needle) {
        EXPECT_NE(err.find("weights.safetensors"), std::string::npos) << err;
        EXPECT_NE(err.find(needle), std::string::npos) << err;
    };
    expect(parse_error("abc"), "shorter than the 8-byte header");
    expect(parse_error(file_bytes(ok_header, data).substr(0, 20)), "header length");
    expect(parse_error(file_bytes(ok_header, data.substr(0, 4))), "outside the 4-byte data section");
    expect(parse_error(file_bytes("{not json", data)), "malformed header");
    expect(parse_error(file_bytes(R"({"w": {"dtype": "F32", "shape": [3], "data_offsets": [0, 8]}})", data)),
           "needs 12 bytes");
    expect(parse_error(file_bytes(R"({"w": {"dtype": "I64", "shape": [1], "data_offsets": [0, 8]}})", data)),
           "unsupported dtype 'I64'");
    expect(parse_error(file_bytes(R"({"w": {"dtype": "F32", "shape": [2]}})", data)), "tensor 'w'");
    expect(parse_error(file_bytes(R"({"a": {"dtype": "F32", "shape": [2], "data_offsets": [0, 8]},
                                      "b": {"dtype": "F32", "shape": [1], "data_offsets": [4, 8]}})",
                                  data)),
           "overlap");
    expect(parse_error(file_bytes(R"({"w": {"dtype": "F32", "shape": [-2], "data_offsets": [0, 8]}})", data)),
           "non-negative");
    test::expect_error_naming([] { SafeTensors::load("/nonexistent/x.safetensors"); },
                              {"/nonexistent/x.safetensors: cannot open"});
}

TEST(SafeTensors, Taesd3WeightsMatchTheirKeyList) {
    std::string shared = test::shared_dir();
    if (shared.empty()) GTEST_SKIP() << "../shared not found (set LATENTPT_SHARED)";
    const std::string dir = shared + "/models/taesd3/";
    std::ifstream keys(dir + "taesd3_keys.txt");
    ASSERT_TRUE(keys) << "taesd3_keys.txt missing";
    // Lines: "# <file> ..." start a file's section; "<name>\t(<shape>)\tmin=<v>\tmax=<v>".
    std::unique_ptr<SafeTensors> st;
    std::regex file_re(R"(^# (\S+\.safetensors))"), row_re(R"(^(\S+)\t\(([0-9, ]*)\)\tmin=(\S+)\tmax=(\S+))");
    int checked = 0;
    for (std::string line; std::getline(keys, line);) {
        std::smatch m;
        if (std::regex_search(line, m, file_re)) {
            st = std::make_unique<SafeTensors>(SafeTensors::load(dir + m[1].str()));
            continue;
        }
        if (!st || !std::regex_search(line, m, row_re)) continue;
        std::vector<int64_t> shape;
        std::stringstream ss(m[2].str());
        for (std::string d; std::getline(ss, d, ',');)
            if (d.find_first_not_of(' ') != std::string::npos) shape.push_back(std::stoll(d));
        std::vector<float> v = st->to_float(m[1].str(), shape);
        auto [lo, hi] = std::minmax_element(v.begin(), v.end());
        // The list prints 4 significant digits of the BF16 values.
        EXPECT_NEAR(*lo, std::stof(m[3].str()), 5e-4f * std::max(1.f, std::abs(*lo))) << m[1];
        EXPECT_NEAR(*hi, std::stof(m[4].str()), 5e-4f * std::max(1.f, std::abs(*hi))) << m[1];
        ++checked;
    }
    EXPECT_GE(checked, 130) << "encoder + decoder tensors";
}
