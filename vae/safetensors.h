// Reader for the safetensors format (8-byte little-endian header length, a JSON header naming
// each tensor's dtype, shape and byte range, then the raw data). Torch-free on purpose: weights
// are validated and converted to float here, and only the network code in vae/ sees libtorch.
// Every inconsistency (truncated file, malformed header, overlapping or out-of-range data, a
// byte count that does not match the shape) is a std::runtime_error naming the file and tensor.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lpt {

enum class TensorDType { F32, F16, BF16 };

struct TensorInfo {
    TensorDType dtype = TensorDType::F32;
    std::vector<int64_t> shape;
    size_t begin = 0, end = 0;  ///< byte range within the data section
    int64_t numel() const;
};

class SafeTensors {
public:
    /// Reads and validates the whole file.
    static SafeTensors load(const std::string& path);
    /// Same, from bytes in memory (`name` only labels errors).
    static SafeTensors parse(std::string bytes, const std::string& name);

    const std::string& path() const { return m_path; }
    bool has(const std::string& tensor) const { return m_tensors.count(tensor) != 0; }
    const std::map<std::string, TensorInfo>& tensors() const { return m_tensors; }
    const std::map<std::string, std::string>& metadata() const { return m_metadata; }
    /// The tensor converted to float32 (row-major). Throws if absent or if `expected_shape` is
    /// given and differs (the message shows both shapes).
    std::vector<float> to_float(const std::string& tensor, const std::vector<int64_t>& expected_shape = {}) const;

private:
    std::string m_path;
    std::string m_bytes;      ///< the whole file
    size_t m_data_start = 0;  ///< offset of the data section
    std::map<std::string, TensorInfo> m_tensors;
    std::map<std::string, std::string> m_metadata;
};

std::string shape_string(const std::vector<int64_t>& shape);
float bf16_to_float(uint16_t v);
float f16_to_float(uint16_t v);

}  // namespace lpt
