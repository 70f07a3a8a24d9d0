#include "core/sample_batch.h"
#include "core/vectorize.h"
#include <stdexcept>

namespace lpt {

namespace {

/// The scrambled coordinate of SobolPairPoint::coordinate from its Sobol word z (bit-reversed).
inline float scrambled_fraction(uint32_t z, uint32_t seed) {
    return float(reverse_bits32(lk_hash(z, seed)) >> 8) * 0x1.0p-24f;
}

/// SobolPairPoint's pair hash and coordinate 0's Sobol word z0 = rev(shuffled_reversed);
/// coordinate 1's is kSobolDimension1Reversed(shuffled_reversed) = sobol_dimension1_unreversed(z0).
struct PairWord {
    uint32_t z0, seed;
};
inline PairWord pair_word(uint64_t key, uint64_t pair_mix, uint32_t index) {
    const uint64_t h = mix64(key ^ pair_mix);
    return {reverse_bits32(lk_hash(reverse_bits32(index), uint32_t(h))), uint32_t(h >> 32)};
}

constexpr uint32_t kSecondSeed = 0x9e3779b9u;  // SobolPairPoint::coordinate(1)'s seed offset

LPT_VECTOR_CLONES
void both_coordinates(const uint64_t* keys, const uint32_t* indices, size_t n, uint64_t pair_mix, float* u0,
                      float* u1) {
#pragma GCC ivdep
    for (size_t k = 0; k < n; ++k) {
        const PairWord w = pair_word(keys[k], pair_mix, indices[k]);
        u0[k] = scrambled_fraction(w.z0, w.seed);
        u1[k] = scrambled_fraction(sobol_dimension1_unreversed(w.z0), w.seed ^ kSecondSeed);
    }
}

/// Coordinate c of the pair alone: SobolPairPoint::coordinate(c).
LPT_VECTOR_CLONES
void one_coordinate(const uint64_t* keys, const uint32_t* indices, size_t n, uint64_t pair_mix, uint32_t c, float* u) {
    const uint32_t seed_offset = c ? kSecondSeed : 0u;
#pragma GCC ivdep
    for (size_t k = 0; k < n; ++k) {
        const PairWord w = pair_word(keys[k], pair_mix, indices[k]);
        u[k] = scrambled_fraction(c ? sobol_dimension1_unreversed(w.z0) : w.z0, w.seed ^ seed_offset);
    }
}

}  // namespace

void sobol_batch(const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t dimension, float* u0, float* u1) {
    const DimensionPair d = dimension_pair(dimension);
    const uint64_t pair_mix = uint64_t(d.pair) * 0xd1b54a32d192ed03ULL;
    if (u1) {
        if (d.coordinate != 0 || dimension_pair(dimension + 1).pair != d.pair)
            throw std::logic_error("sobol_batch: dimensions " + std::to_string(dimension) + " and " +
                                   std::to_string(dimension + 1) + " are not one pair");
        both_coordinates(keys, indices, n, pair_mix, u0, u1);
    } else {
        one_coordinate(keys, indices, n, pair_mix, d.coordinate, u0);
    }
}

void sample_batch(SamplerKind kind, const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t dimension,
                  float* u0, float* u1) {
    if (kind == SamplerKind::Sobol) return sobol_batch(keys, indices, n, dimension, u0, u1);
    for (size_t k = 0; k < n; ++k) {
        const SampleStream rng = SampleStream::from_key(keys[k], indices[k], kind);
        if (u1) rng.get2(dimension, u0[k], u1[k]);
        else u0[k] = rng.get(dimension);
    }
}

}  // namespace lpt
