// Deterministic samplers: every random number is a pure function of
// (sampler kind, seed, pixel, sample index, dimension), so any pass (primal, adjoint replay,
// another thread count) regenerates exactly the same numbers. Dimension layout and the
// low-discrepancy construction: docs/sampling.md.
#pragma once
#include <cstdint>
#include <optional>
#include <stdexcept>
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
    x = __builtin_bswap32(x);  // one instruction for the byte-level half of the reversal
    x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
    x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
    return ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
}

/// Laine-Karras style hash: bit t of the result depends on the seed and on bits <= t of x only (a
/// multiply by an even constant moves information only towards more significant bits). Constants
/// from Vegdahl's search for better-avalanching variants of Burley's (JCGT 2020) hash.
inline uint32_t lk_hash(uint32_t x, uint32_t seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

/// Nested uniform (Owen) scramble of a 32-bit binary fraction: each bit is flipped by a hash of the
/// seed and of the more significant bits only, so aligned dyadic intervals map onto aligned dyadic
/// intervals: lk_hash on the bit-reversed value.
inline uint32_t owen_scramble(uint32_t x, uint32_t seed) { return reverse_bits32(lk_hash(reverse_bits32(x), seed)); }

/// The first two dimensions of the Sobol sequence as 32-bit fractions: van der Corput (radix
/// inverse), and the dimension of primitive polynomial x + 1 (direction v_k = v_{k-1} ^ v_{k-1} >> 1).
inline uint32_t sobol_dimension0(uint32_t index) { return reverse_bits32(index); }

/// A linear map of 32 bits (over GF(2)) applied a byte at a time: entry [b][e] is the XOR of the
/// images of the set bits of e placed at byte b. Four lookups instead of a 32-round bit loop (the
/// shuffled index has all 32 bits in play).
struct BitMatrixTable {
    uint32_t t[4][256];
    /// column(k): the image of bit k.
    template <class Column>
    constexpr explicit BitMatrixTable(Column column) : t{} {
        for (int b = 0; b < 4; ++b)
            for (int e = 0; e < 256; ++e) {
                uint32_t x = 0;
                for (int k = 0; k < 8; ++k)
                    if (e >> k & 1) x ^= column(8 * b + k);
                t[b][e] = x;
            }
    }
    constexpr uint32_t operator()(uint32_t v) const {
        return t[0][v & 0xffu] ^ t[1][(v >> 8) & 0xffu] ^ t[2][(v >> 16) & 0xffu] ^ t[3][v >> 24];
    }
};

constexpr uint32_t sobol_direction1(int k) {  // v_k of dimension 1
    uint32_t v = 1u << 31;
    for (int i = 0; i < k; ++i) v ^= v >> 1;
    return v;
}
constexpr uint32_t reverse_bits32_constexpr(uint32_t x) {
    uint32_t r = 0;
    for (int i = 0; i < 32; ++i) r |= ((x >> i) & 1u) << (31 - i);
    return r;
}
/// sobol_dimension1 itself, and the same map between bit-reversed words: reversed(sobol_1(reversed(z))),
/// which lets the sampler stay in bit-reversed order between its two scrambles.
inline constexpr BitMatrixTable kSobolDimension1{[](int k) { return sobol_direction1(k); }};
inline constexpr BitMatrixTable kSobolDimension1Reversed{
    [](int k) { return reverse_bits32_constexpr(sobol_direction1(31 - k)); }};

inline uint32_t sobol_dimension1(uint32_t index) { return kSobolDimension1(index); }

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

/// One pair's point for one sample, computed in bit-reversed order where it saves reversals:
///   shuffled = owen(index, h_lo)            (padding: a different aligned block of the sequence)
///   x_c      = owen(sobol_c(shuffled), h_hi ^ c)
/// with owen(x) = rev(lk(rev(x))) and rev(shuffled) = lk(rev(index), h_lo):
///   x_0 = rev(lk(shuffled, s_0)),  x_1 = rev(lk(R(rev(shuffled)), s_1)),  R = rev ∘ sobol_1 ∘ rev.
struct SobolPairPoint {
    uint64_t h;
    uint32_t shuffled_reversed;
    SobolPairPoint(uint64_t pixel_key, uint32_t pair, uint32_t reversed_index)
        : h(mix64(pixel_key ^ (uint64_t(pair) * 0xd1b54a32d192ed03ULL))),
          shuffled_reversed(lk_hash(reversed_index, uint32_t(h))) {}
    /// Coordinate 0's Sobol word; coordinate 1's is kSobolDimension1Reversed(shuffled_reversed).
    uint32_t word0() const { return reverse_bits32(shuffled_reversed); }
    /// Coordinate c's scrambling seed.
    uint32_t seed(uint32_t c) const { return uint32_t(h >> 32) ^ (c ? 0x9e3779b9u : 0u); }
    /// Sobol word z, Owen-scrambled under `seed`, as a float in [0, 1).
    static float scrambled(uint32_t z, uint32_t seed) {
        return float(reverse_bits32(lk_hash(z, seed)) >> 8) * 0x1.0p-24f;
    }
    float coordinate(uint32_t c) const {
        return scrambled(c == 0 ? word0() : kSobolDimension1Reversed(shuffled_reversed), seed(c));
    }
};

/// Sample `index` of a pixel (its key) in `dimension`, in [0, 1).
inline float sobol_sample(uint64_t pixel_key, uint32_t index, uint32_t dimension) {
    const DimensionPair d = dimension_pair(dimension);
    return SobolPairPoint(pixel_key, d.pair, reverse_bits32(index)).coordinate(d.coordinate);
}

/// A per-sample view: the key is hashed once, each dimension costs one more mix (independent) or
/// one scrambled Sobol coordinate (Sobol); get2 draws both coordinates of a pair for little more
/// than one.
struct SampleStream {
    uint64_t key;
    uint32_t index = 0;
    uint32_t reversed_index = 0;  ///< Sobol: reverse_bits32(index), shared by every dimension
    SamplerKind kind = SamplerKind::Independent;
    SampleStream(uint64_t seed, uint32_t pixel, uint32_t sample_index, SamplerKind k = SamplerKind::Independent)
        : SampleStream(k == SamplerKind::Sobol ? sobol_pixel_key(seed, pixel) : sample_key(seed, pixel, sample_index),
                       sample_index, k) {}
    /// From a key hashed earlier (the tracer keeps one per path instead of rehashing per stage).
    static SampleStream from_key(uint64_t key, uint32_t sample_index, SamplerKind k) {
        return SampleStream(key, sample_index, k);
    }
    float get(uint32_t dimension) const {
        if (kind != SamplerKind::Sobol) return sample_from_key(key, dimension);
        const DimensionPair d = dimension_pair(dimension);
        return SobolPairPoint(key, d.pair, reversed_index).coordinate(d.coordinate);
    }
    /// get(dimension) and get(dimension + 1), which must be coordinates 0 and 1 of one pair (the
    /// filter, light position and BSDF direction pairs of the layout).
    void get2(uint32_t dimension, float& u0, float& u1) const {
        if (kind != SamplerKind::Sobol) {
            u0 = sample_from_key(key, dimension);
            u1 = sample_from_key(key, dimension + 1);
            return;
        }
        const SobolPairPoint p(key, dimension_pair(dimension).pair, reversed_index);
        u0 = p.coordinate(0);
        u1 = p.coordinate(1);
    }

private:
    SampleStream(uint64_t k, uint32_t i, SamplerKind s)
        : key(k), index(i), reversed_index(s == SamplerKind::Sobol ? reverse_bits32(i) : 0), kind(s) {}
};

/// get2's precondition, checked at compile time for the pairs the tracer draws together.
static_assert(dimension_pair(dim::kFilter).coordinate == 0 &&
              dimension_pair(dim::kFilter + 1).pair == dimension_pair(dim::kFilter).pair);
static_assert(dimension_pair(dim::bounce(3, dim::kLightPos)).coordinate == 0 &&
              dimension_pair(dim::bounce(3, dim::kLightPos + 1)).pair ==
                  dimension_pair(dim::bounce(3, dim::kLightPos)).pair);
static_assert(dimension_pair(dim::bounce(3, dim::kBsdfDir)).coordinate == 0 &&
              dimension_pair(dim::bounce(3, dim::kBsdfDir + 1)).pair ==
                  dimension_pair(dim::bounce(3, dim::kBsdfDir)).pair);

/// What regenerates a render's random numbers: its seed and sampler kind (path replay keeps it).
struct SamplerId {
    uint64_t seed = 0;
    SamplerKind kind = SamplerKind::Sobol;
    SampleStream stream(uint32_t pixel, uint32_t sample_index) const {
        return SampleStream(seed, pixel, sample_index, kind);
    }
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
/// parse_sampler for a caller's value: throws std::invalid_argument naming `option` for any other word.
inline SamplerKind sampler_named(const std::string& name, const std::string& option = "sampler") {
    SamplerKind k;
    if (!parse_sampler(name, k))
        throw std::invalid_argument(option + " must be 'sobol' or 'independent', got '" + name + "'");
    return k;
}
/// An optional choice that replaces a scene's: "" = none (the scene's own), else sampler_named's.
inline std::optional<SamplerKind> sampler_choice(const std::string& name, const std::string& option = "sampler") {
    if (name.empty()) return std::nullopt;
    return sampler_named(name, option);
}

/// The BSDF sample's random numbers at a depth: lobe choice and direction. Path replay re-samples
/// delta lobes with them (autodiff/path_record.cpp); the tracer draws the same numbers for its
/// whole shade queue at once (core/sample_batch.h).
struct BsdfRandoms {
    float lobe;
    float dir[2];
};
inline BsdfRandoms bsdf_randoms(const SampleStream& rng, uint32_t depth) {
    BsdfRandoms u;
    u.lobe = rng.get(dim::bounce(depth, dim::kBsdfLobe));
    rng.get2(dim::bounce(depth, dim::kBsdfDir), u.dir[0], u.dir[1]);
    return u;
}

}  // namespace lpt
