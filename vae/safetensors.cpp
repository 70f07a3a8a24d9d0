#include "vae/safetensors.h"
#include <nlohmann/json.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace lpt {

namespace {
[[noreturn]] void fail(const std::string& file, const std::string& msg) { throw std::runtime_error(file + ": " + msg); }

size_t dtype_size(TensorDType t) { return t == TensorDType::F32 ? 4 : 2; }
}  // namespace

int64_t TensorInfo::numel() const {
    int64_t n = 1;
    for (int64_t d : shape) n *= d;
    return n;
}

std::string shape_string(const std::vector<int64_t>& shape) {
    std::string s = "[";
    for (size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + "]";
}

float bf16_to_float(uint16_t v) {  // bfloat16 is the top half of an IEEE float32
    uint32_t bits = uint32_t(v) << 16;
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

float f16_to_float(uint16_t v) {
    const uint32_t sign = uint32_t(v & 0x8000) << 16, exp = (v >> 10) & 0x1f, mant = v & 0x3ff;
    float f;
    if (exp == 0) {
        f = std::ldexp(float(mant), -24);  // subnormal (or zero)
        return sign ? -f : f;
    }
    uint32_t bits = exp == 31 ? sign | 0x7f800000u | (mant << 13) : sign | ((exp + 112) << 23) | (mant << 13);
    std::memcpy(&f, &bits, 4);
    return f;
}

SafeTensors SafeTensors::load(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, "cannot open file");
    std::ostringstream ss;
    ss << in.rdbuf();
    return parse(ss.str(), path);
}

SafeTensors SafeTensors::parse(std::string bytes, const std::string& name) {
    SafeTensors st;
    st.m_path = name;
    if (bytes.size() < 8) fail(name, "truncated: shorter than the 8-byte header length");
    uint64_t n = 0;
    for (int i = 7; i >= 0; --i) n = (n << 8) | uint8_t(bytes[i]);
    if (n > bytes.size() - 8)
        fail(name, "truncated: header length " + std::to_string(n) + " exceeds the file (" +
                       std::to_string(bytes.size()) + " bytes)");
    nlohmann::json h;
    try {
        h = nlohmann::json::parse(bytes.begin() + 8, bytes.begin() + 8 + long(n));
    } catch (const nlohmann::json::exception& e) {
        fail(name, std::string("malformed header: ") + e.what());
    }
    if (!h.is_object()) fail(name, "malformed header: not a JSON object");
    st.m_data_start = 8 + n;
    const size_t data_size = bytes.size() - st.m_data_start;
    std::vector<std::pair<size_t, size_t>> ranges;
    for (const auto& [key, v] : h.items()) {
        if (key == "__metadata__") {
            if (!v.is_object()) fail(name, "__metadata__ is not an object");
            for (const auto& [mk, mv] : v.items())
                if (mv.is_string()) st.m_metadata[mk] = mv.get<std::string>();
            continue;
        }
        const std::string where = "tensor '" + key + "'";
        if (!v.is_object() || !v.contains("dtype") || !v.contains("shape") || !v.contains("data_offsets"))
            fail(name, where + ": needs dtype, shape and data_offsets");
        TensorInfo t;
        const std::string dt = v["dtype"].is_string() ? v["dtype"].get<std::string>() : "";
        if (dt == "F32") t.dtype = TensorDType::F32;
        else if (dt == "F16") t.dtype = TensorDType::F16;
        else if (dt == "BF16") t.dtype = TensorDType::BF16;
        else fail(name, where + ": unsupported dtype '" + dt + "' (supported: F32, F16, BF16)");
        if (!v["shape"].is_array()) fail(name, where + ": shape is not an array");
        for (const auto& d : v["shape"]) {
            if (!d.is_number_integer() || d.get<int64_t>() < 0)
                fail(name, where + ": shape entries must be non-negative integers");
            t.shape.push_back(d.get<int64_t>());
        }
        const auto& off = v["data_offsets"];
        if (!off.is_array() || off.size() != 2 || !off[0].is_number_unsigned() || !off[1].is_number_unsigned())
            fail(name, where + ": data_offsets must be two non-negative integers");
        t.begin = off[0].get<size_t>();
        t.end = off[1].get<size_t>();
        if (t.begin > t.end || t.end > data_size)
            fail(name, where + ": data_offsets [" + std::to_string(t.begin) + ", " + std::to_string(t.end) +
                           "] outside the " + std::to_string(data_size) + "-byte data section (truncated file?)");
        if (uint64_t(t.numel()) * dtype_size(t.dtype) != t.end - t.begin)
            fail(name, where + ": shape " + shape_string(t.shape) + " of " + dt + " needs " +
                           std::to_string(t.numel() * dtype_size(t.dtype)) + " bytes, data_offsets give " +
                           std::to_string(t.end - t.begin));
        ranges.emplace_back(t.begin, t.end);
        st.m_tensors[key] = t;
    }
    std::sort(ranges.begin(), ranges.end());
    for (size_t i = 1; i < ranges.size(); ++i)
        if (ranges[i].first < ranges[i - 1].second) fail(name, "tensors overlap in the data section");
    st.m_bytes = std::move(bytes);
    return st;
}

std::vector<float> SafeTensors::to_float(const std::string& tensor, const std::vector<int64_t>& expected_shape) const {
    auto it = m_tensors.find(tensor);
    if (it == m_tensors.end()) fail(m_path, "no tensor '" + tensor + "'");
    const TensorInfo& t = it->second;
    if (!expected_shape.empty() && expected_shape != t.shape)
        fail(m_path, "tensor '" + tensor + "' has shape " + shape_string(t.shape) + ", expected " +
                         shape_string(expected_shape));
    std::vector<float> out(size_t(t.numel()));
    const char* p = m_bytes.data() + m_data_start + t.begin;
    for (size_t i = 0; i < out.size(); ++i) {
        if (t.dtype == TensorDType::F32) {
            std::memcpy(&out[i], p + 4 * i, 4);
        } else {
            uint16_t v = uint16_t(uint8_t(p[2 * i])) | uint16_t(uint16_t(uint8_t(p[2 * i + 1])) << 8);
            out[i] = t.dtype == TensorDType::BF16 ? bf16_to_float(v) : f16_to_float(v);
        }
    }
    return out;
}

}  // namespace lpt
