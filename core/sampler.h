// Deterministic samplers: every random number is a pure function of
// (sampler kind, seed, pixel, sample index, dimension), so any pass (primal, adjoint replay,
// another thread count) regenerates exactly the same numbers. Dimension layout and the
// low-discrepancy construction: docs/sampling.md.
#pragma once
#include <cstdint>
#include <string>

namespace lpt {

/// Where a render's random numbers come from. Independent: hashed white noise per dimension.
/// Sobol: per pixel, each pair of dimensions is an Owen-scrambled 2D Sobol (0,2)-sequence with a
/// shuffled index (padding), so every power-of-two prefix of a pixel's samples is stratified in
/// every elementary interval of each pair (docs/sampling.md (8)-(10)).
enum class SamplerKind : uint8_t { Independent, Sobol };

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

/// Uniform float in [0, 1): the independent sampler (also the tests' hash-based point sets).
inline float sample_1d(uint64_t seed, uint32_t pixel, uint32_t sample_index, uint32_t dimension) {
    return sample_from_key(sample_key(seed, pixel, sample_index), dimension);
}

// ---- Owen-scrambled Sobol (docs/sampling.md (8)-(10)) --------------------------------------

inline uint32_t reverse_bits32(uint32_t x) {
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
    x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
    return ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
}

/// Nested uniform (Owen) scramble of a 32-bit binary fraction: each bit is flipped by a hash of the
/// seed and of the more significant bits only, so aligned dyadic intervals map onto aligned dyadic
/// intervals. A Laine-Karras style hash on the bit-reversed value (a multiply by an even constant
/// moves information only towards more significant bits); constants from Vegdahl's search for
/// better-avalanching variants of Burley's (JCGT 2020) hash.
inline uint32_t owen_scramble(uint32_t x, uint32_t seed) {
    x = reverse_bits32(x);
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return reverse_bits32(x);
}

/// The first two dimensions of the Sobol sequence as 32-bit fractions: van der Corput (radix
/// inverse), and the dimension of primitive polynomial x + 1 (direction v_k = v_{k-1} ^ v_{k-1} >> 1).
inline uint32_t sobol_dimension0(uint32_t index) { return reverse_bits32(index); }
inline uint32_t sobol_dimension1(uint32_t index) {
    uint32_t x = 0;
    for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1)
        if (index & 1u) x ^= v;
    return x;
}

/// Which 2D pair, and which coordinate of it, a dimension of docs/sampling.md's layout belongs to.
/// Pairs are chosen so that 2D decisions are stratified jointly: filter (x, y), light position,
/// BSDF direction; the 1D choices share the remaining pairs.
struct DimensionPair {
    uint32_t pair, coordinate;
};
constexpr DimensionPair dimension_pair(uint32_t dimension) {
    if (dimension < 4) return {dimension / 2, dimension % 2};
    // Per bounce, offsets: light choice 0, light position 1-2, lobe 3, direction 4-5, RR 6, spare 7.
    constexpr uint32_t pair_of[8] = {2, 0, 0, 2, 1, 1, 3, 3}, coordinate_of[8] = {0, 0, 1, 1, 0, 1, 0, 1};
    const uint32_t b = (dimension - 4) / 8, o = (dimension - 4) % 8;
    return {2 + 4 * b + pair_of[o], coordinate_of[o]};
}

/// Per-pixel key of the Sobol sampler: the part shared by every sample and dimension of a pixel.
inline uint64_t sobol_pixel_key(uint64_t seed, uint32_t pixel) {
    return mix64(mix64(seed ^ 0x5851f42d4c957f2dULL) + pixel);
}

/// Sample `index` of a pixel (its key) in `dimension`, in [0, 1).
inline float sobol_sample(uint64_t pixel_key, uint32_t index, uint32_t dimension) {
    const DimensionPair d = dimension_pair(dimension);
    const uint64_t h = mix64(pixel_key ^ (uint64_t(d.pair) * 0xd1b54a32d192ed03ULL));
    // Shuffling the index by an Owen scramble keeps each power-of-two prefix inside one aligned
    // block of the sequence (itself a (0,m,2)-net) while decorrelating the pairs (padding).
    const uint32_t shuffled = owen_scramble(index, uint32_t(h));
    const uint32_t x = d.coordinate == 0 ? sobol_dimension0(shuffled) : sobol_dimension1(shuffled);
    const uint32_t scramble_seed = uint32_t(h >> 32) ^ (d.coordinate ? 0x9e3779b9u : 0u);
    return float(owen_scramble(x, scramble_seed) >> 8) * 0x1.0p-24f;
}

/// A per-sample view: the key is hashed once, each dimension costs one more mix (independent) or
/// one scrambled Sobol point (Sobol).
struct SampleStream {
    uint64_t key;
    uint32_t index = 0;
    SamplerKind kind = SamplerKind::Independent;
    SampleStream(uint64_t seed, uint32_t pixel, uint32_t sample_index, SamplerKind k = SamplerKind::Independent)
        : key(k == SamplerKind::Sobol ? sobol_pixel_key(seed, pixel) : sample_key(seed, pixel, sample_index)),
          index(sample_index), kind(k) {}
    /// From a key hashed earlier (the tracer keeps one per path instead of rehashing per stage).
    static SampleStream from_key(uint64_t key, uint32_t sample_index, SamplerKind k) { return SampleStream(key, sample_index, k); }
    float get(uint32_t dimension) const {
        return kind == SamplerKind::Sobol ? sobol_sample(key, index, dimension) : sample_from_key(key, dimension);
    }

private:
    SampleStream(uint64_t k, uint32_t i, SamplerKind s) : key(k), index(i), kind(s) {}
};

/// What regenerates a render's random numbers: its seed and sampler kind (path replay keeps it).
struct SamplerId {
    uint64_t seed = 0;
    SamplerKind kind = SamplerKind::Independent;
    SampleStream stream(uint32_t pixel, uint32_t sample_index) const { return SampleStream(seed, pixel, sample_index, kind); }
};

/// "independent" / "sobol" (the CLI's and the scene files' spelling).
inline const char* sampler_name(SamplerKind k) { return k == SamplerKind::Sobol ? "sobol" : "independent"; }
/// Parses sampler_name's spelling; false for anything else.
inline bool parse_sampler(const std::string& name, SamplerKind& out) {
    if (name == "sobol") out = SamplerKind::Sobol;
    else if (name == "independent") out = SamplerKind::Independent;
    else return false;
    return true;
}

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
