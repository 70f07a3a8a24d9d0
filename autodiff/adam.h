// Adam over one flat parameter buffer (the ParamStore's raw values), blind to what the values
// mean. Update rule: docs/fitting.md (10)–(12); checkpoint blob: docs/fitting.md, "Adam state".
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lpt {

/// Everything a resumed fit needs besides the parameters: first/second moments (one per
/// parameter) and the number of steps taken (drives the bias correction).
struct AdamState {
    std::vector<float> m, v;
    int64_t step = 0;
};

struct AdamConfig {
    float beta1 = 0.9f;
    float beta2 = 0.999f;
    /// Added to sqrt(v̂), as PyTorch's torch.optim.Adam does (not inside the square root).
    float eps = 1e-8f;
};

class Adam {
public:
    /// An optimiser for n parameters, zero moments, step 0. Throws std::invalid_argument if a
    /// beta is outside [0, 1) or eps < 0.
    explicit Adam(size_t n, AdamConfig config = {});

    /// One Adam step with learning rate lr: params[i] -= lr · m̂ᵢ / (sqrt(v̂ᵢ) + eps).
    /// Returns the number of non-finite entries of grads. If it is non-zero, nothing is changed
    /// (params, m, v and step): the caller skips the iteration, counts it and warns.
    /// Throws std::invalid_argument if n differs from size() or lr is not finite.
    size_t step(float* params, const float* grads, size_t n, float lr);

    size_t size() const { return m_state.m.size(); }
    const AdamConfig& config() const { return m_config; }
    const AdamState& state() const { return m_state; }
    /// Replaces the state (checkpoint resume). Throws std::runtime_error if m or v does not have
    /// size() entries or step < 0.
    void set_state(AdamState state);

private:
    AdamConfig m_config;
    AdamState m_state;
};

/// AdamState → binary blob: magic "LPTADAM\0", u32 version (1), i64 step, u64 n, n floats m,
/// n floats v, all in the host's (little-endian) byte order. Throws std::invalid_argument if
/// m and v differ in size.
std::string serialize_adam_state(const AdamState& state);
/// Inverse of serialize_adam_state. Throws std::runtime_error on a wrong magic or version, a
/// truncated or over-long blob, or a negative step.
AdamState deserialize_adam_state(const std::string& blob);

}  // namespace lpt
