// Deterministic sampler: every random number is a pure function of
// (seed, pixel, sample index, dimension), so any pass (primal, adjoint replay, another thread
// count) regenerates exactly the same numbers. Dimension layout: docs/sampling.md.
#pragma once
#include <cstdint>

namespace lpt {

/// Dimensions used by one camera path. Camera: filter (2). Each bounce b uses the block
/// kBounceBase + kDimsPerBounce * b: light choice (1), light position (2), BSDF lobe (1),
/// BSDF direction (2), Russian roulette (1), spare (1).
namespace dim {
constexpr uint32_t kFilter = 0;
constexpr uint32_t kBounceBase = 4;
constexpr uint32_t kDimsPerBounce = 8;
constexpr uint32_t kLightChoice = 0, kLightPos = 1, kBsdfLobe = 3, kBsdfDir = 4, kRR = 6;
constexpr uint32_t bounce(uint32_t depth, uint32_t offset) { return kBounceBase + kDimsPerBounce * depth + offset; }
}  // namespace dim

inline uint64_t mix64(uint64_t z) {  // splitmix64 finaliser: full-avalanche 64-bit mix
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/// Uniform float in [0, 1).
inline float sample_1d(uint64_t seed, uint32_t pixel, uint32_t sample_index, uint32_t dimension) {
    uint64_t h = mix64(seed + 0x9e3779b97f4a7c15ULL);
    h = mix64(h ^ (uint64_t(pixel) << 32 | sample_index));
    h = mix64(h ^ (uint64_t(dimension) * 0xd1b54a32d192ed03ULL));
    return float(h >> 40) * 0x1.0p-24f;
}

/// A per-sample view: seed, pixel and sample index fixed, dimensions drawn on demand.
struct SampleStream {
    uint64_t seed;
    uint32_t pixel, index;
    float get(uint32_t dimension) const { return sample_1d(seed, pixel, index, dimension); }
};

}  // namespace lpt
