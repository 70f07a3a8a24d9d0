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

/// Hash of the (seed, pixel, sample index) key: the part shared by all dimensions of a sample.
inline uint64_t sample_key(uint64_t seed, uint32_t pixel, uint32_t sample_index) {
    return mix64(mix64(seed + 0x9e3779b97f4a7c15ULL) ^ (uint64_t(pixel) << 32 | sample_index));
}

inline float sample_from_key(uint64_t key, uint32_t dimension) {
    return float(mix64(key ^ (uint64_t(dimension) * 0xd1b54a32d192ed03ULL)) >> 40) * 0x1.0p-24f;
}

/// Uniform float in [0, 1).
inline float sample_1d(uint64_t seed, uint32_t pixel, uint32_t sample_index, uint32_t dimension) {
    return sample_from_key(sample_key(seed, pixel, sample_index), dimension);
}

/// A per-sample view: the key is hashed once, each dimension costs one more mix.
struct SampleStream {
    uint64_t key;
    SampleStream(uint64_t seed, uint32_t pixel, uint32_t index) : key(sample_key(seed, pixel, index)) {}
    /// From a key hashed earlier (the tracer keeps one per path instead of rehashing per stage).
    static SampleStream from_key(uint64_t key) { return SampleStream(key); }
    float get(uint32_t dimension) const { return sample_from_key(key, dimension); }

private:
    explicit SampleStream(uint64_t k) : key(k) {}
};

/// The BSDF sample's random numbers at a depth: lobe choice and direction. Shared by the tracer
/// and by path replay, which re-samples delta lobes (autodiff/path_record.cpp).
struct BsdfRandoms {
    float lobe;
    float dir[2];
};
inline BsdfRandoms bsdf_randoms(const SampleStream& rng, uint32_t depth) {
    return {rng.get(dim::bounce(depth, dim::kBsdfLobe)), {rng.get(dim::bounce(depth, dim::kBsdfDir)), rng.get(dim::bounce(depth, dim::kBsdfDir + 1))}};
}

}  // namespace lpt
