#include "core/sample_batch.h"
#include "core/vectorize.h"
#include <stdexcept>

namespace lpt {

namespace {

// Both loops compute SobolPairPoint::coordinate, with coordinate 1's Sobol word by
// sobol_dimension1_unreversed instead of the table lookup, which GCC does not vectorise.
LPT_VECTOR_CLONES
void both_coordinates(const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t pair, float* u0, float* u1) {
#pragma GCC ivdep
    for (size_t k = 0; k < n; ++k) {
        const SobolPairPoint pt(keys[k], pair, reverse_bits32(indices[k]));
        const uint32_t z0 = pt.word0();
        u0[k] = SobolPairPoint::scrambled(z0, pt.seed(0));
        u1[k] = SobolPairPoint::scrambled(sobol_dimension1_unreversed(z0), pt.seed(1));
    }
}

/// Coordinate c of the pair alone: SobolPairPoint::coordinate(c).
LPT_VECTOR_CLONES
void one_coordinate(const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t pair, uint32_t c, float* u) {
#pragma GCC ivdep
    for (size_t k = 0; k < n; ++k) {
        const SobolPairPoint pt(keys[k], pair, reverse_bits32(indices[k]));
        const uint32_t z0 = pt.word0();
        u[k] = SobolPairPoint::scrambled(c ? sobol_dimension1_unreversed(z0) : z0, pt.seed(c));
    }
}

}  // namespace

void sobol_batch(const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t dimension, float* u0, float* u1) {
    const DimensionPair d = dimension_pair(dimension);
    if (u1) {
        if (d.coordinate != 0 || dimension_pair(dimension + 1).pair != d.pair)
            throw std::logic_error("sobol_batch: dimensions " + std::to_string(dimension) + " and " +
                                   std::to_string(dimension + 1) + " are not one pair");
        both_coordinates(keys, indices, n, d.pair, u0, u1);
    } else {
        one_coordinate(keys, indices, n, d.pair, d.coordinate, u0);
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

void bsdf_randoms_batch(SamplerKind kind, const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t depth,
                        float* lobe, float* dir0, float* dir1) {
    sample_batch(kind, keys, indices, n, dim::bounce(depth, dim::kBsdfLobe), lobe);
    sample_batch(kind, keys, indices, n, dim::bounce(depth, dim::kBsdfDir), dir0, dir1);
}

}  // namespace lpt
