// Adam (Kingma & Ba 2015) with PyTorch's eps placement: docs/fitting.md (10)–(12).
// The step refuses non-finite gradients wholesale: one NaN folded into m or v would poison that
// parameter for ~1/(1 − β2) = 1000 steps, and a partial update would make the fit depend on
// which entries happened to be finite.
#include "autodiff/adam.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace lpt {

Adam::Adam(size_t n, AdamConfig config) : m_config(config) {
    auto in_unit = [](float b) { return b >= 0.0f && b < 1.0f; };
    if (!in_unit(config.beta1) || !in_unit(config.beta2))
        throw std::invalid_argument("Adam: beta1 and beta2 must lie in [0, 1)");
    if (!(config.eps >= 0.0f)) throw std::invalid_argument("Adam: eps must be >= 0");
    m_state.m.assign(n, 0.0f);
    m_state.v.assign(n, 0.0f);
}

size_t Adam::step(float* params, const float* grads, size_t n, float lr) {
    if (n != size())
        throw std::invalid_argument("Adam::step: " + std::to_string(n) + " parameters, optimiser has " +
                                    std::to_string(size()));
    if (!std::isfinite(lr)) throw std::invalid_argument("Adam::step: learning rate is not finite");

    size_t bad = 0;
    // A gradient whose square overflows would make the second moment infinite for good.
    for (size_t i = 0; i < n; ++i) bad += !std::isfinite(grads[i]) || !std::isfinite(grads[i] * grads[i]);
    if (bad > 0) return bad;

    const float b1 = m_config.beta1, b2 = m_config.beta2;
    const int64_t t = ++m_state.step;
    // Bias corrections in double: β2^t stays accurate for the t ~ 1e3–1e5 of a fit.
    const double bc1 = 1.0 - std::pow(double(b1), double(t));
    const double bc2 = 1.0 - std::pow(double(b2), double(t));
    // docs/fitting.md (12) rearranged as PyTorch does, so the per-element work is one division:
    // Δ = (lr / bc1) · m / (sqrt(v) / sqrt(bc2) + eps).
    const float step_size = float(double(lr) / bc1);
    const float inv_sqrt_bc2 = float(1.0 / std::sqrt(bc2));
    float* m = m_state.m.data();
    float* v = m_state.v.data();
    for (size_t i = 0; i < n; ++i) {
        const float g = grads[i];
        m[i] = b1 * m[i] + (1.0f - b1) * g;
        v[i] = b2 * v[i] + (1.0f - b2) * g * g;
        const float denom = std::sqrt(v[i]) * inv_sqrt_bc2 + m_config.eps;
        params[i] -= step_size * m[i] / denom;
    }
    return 0;
}

void Adam::set_state(AdamState state) {
    if (state.m.size() != size() || state.v.size() != size())
        throw std::runtime_error("Adam::set_state: state holds " + std::to_string(state.m.size()) + "/" +
                                 std::to_string(state.v.size()) + " moments, optimiser has " + std::to_string(size()) +
                                 " parameters");
    if (state.step < 0) throw std::runtime_error("Adam::set_state: negative step count");
    m_state = std::move(state);
}

namespace {

static_assert(sizeof(float) == 4, "the blob stores IEEE-754 binary32 moments");
constexpr char k_magic[8] = {'L', 'P', 'T', 'A', 'D', 'A', 'M', '\0'};
constexpr uint32_t k_version = 1;
constexpr size_t k_header = sizeof(k_magic) + sizeof(uint32_t) + sizeof(int64_t) + sizeof(uint64_t);

template <typename T>
void put(std::string& out, const T& value) {
    out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T get(const std::string& in, size_t& pos) {
    T value;
    std::memcpy(&value, in.data() + pos, sizeof(T));
    pos += sizeof(T);
    return value;
}

}  // namespace

std::string serialize_adam_state(const AdamState& state) {
    if (state.m.size() != state.v.size()) throw std::invalid_argument("serialize_adam_state: m and v differ in size");
    const uint64_t n = state.m.size();
    std::string out;
    out.reserve(k_header + 2 * n * sizeof(float));
    out.append(k_magic, sizeof(k_magic));
    put(out, k_version);
    put(out, int64_t(state.step));
    put(out, n);
    out.append(reinterpret_cast<const char*>(state.m.data()), n * sizeof(float));
    out.append(reinterpret_cast<const char*>(state.v.data()), n * sizeof(float));
    return out;
}

AdamState deserialize_adam_state(const std::string& blob) {
    if (blob.size() < k_header)
        throw std::runtime_error("Adam state: truncated header (" + std::to_string(blob.size()) + " bytes)");
    if (std::memcmp(blob.data(), k_magic, sizeof(k_magic)) != 0)
        throw std::runtime_error("Adam state: bad magic (not an Adam state blob)");
    size_t pos = sizeof(k_magic);
    const auto version = get<uint32_t>(blob, pos);
    if (version != k_version) throw std::runtime_error("Adam state: unsupported version " + std::to_string(version));
    AdamState state;
    state.step = get<int64_t>(blob, pos);
    const auto n = get<uint64_t>(blob, pos);
    if (state.step < 0) throw std::runtime_error("Adam state: negative step count");
    // Compare against the bytes present before multiplying, so a corrupt n can neither overflow
    // nor trigger a huge allocation.
    const uint64_t payload = blob.size() - k_header;
    if (n > payload / (2 * sizeof(float)) || payload != n * 2 * sizeof(float))
        throw std::runtime_error("Adam state: " + std::to_string(payload) + " payload bytes for " + std::to_string(n) +
                                 " parameters (truncated or mismatched)");
    state.m.resize(n);
    state.v.resize(n);
    if (n == 0) return state;  // memcpy from data() of an empty vector is not guaranteed valid
    std::memcpy(state.m.data(), blob.data() + pos, n * sizeof(float));
    std::memcpy(state.v.data(), blob.data() + pos + n * sizeof(float), n * sizeof(float));
    return state;
}

}  // namespace lpt
