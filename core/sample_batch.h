// A stage's random numbers for a whole shade queue at once: the same bits as SampleStream::get /
// get2 (core/sampler.h), the Owen-scrambled Sobol sampler's in a loop GCC vectorises
// (core/vectorize.h). One sample's Sobol coordinate is a dependent chain (reverse, hash, reverse)
// that a path vertex's loop body cannot overlap with the next vertex's; computed 4-8 wide it
// costs a fraction of that.
#pragma once
#include "core/sampler.h"
#include <cstddef>
#include <cstdint>

namespace lpt {

/// sobol_dimension1 before its final bit reversal, without a table: the generator matrix of
/// Sobol's dimension 1 is Pascal's triangle mod 2, whose entry (j, k) is 1 exactly when j's bits
/// are a subset of k's (Lucas), so bit j of the result is the XOR of the index's bits at the
/// positions that contain j: five shift steps (docs/sampling.md). Hence
///   sobol_dimension1(x) = rev(sobol_dimension1_unreversed(x)),
///   kSobolDimension1Reversed(w) = sobol_dimension1_unreversed(rev(w)),
/// on every word (linear maps: the tests compare the 32 unit vectors).
constexpr uint32_t sobol_dimension1_unreversed(uint32_t x) {
    x ^= (x >> 1) & 0x55555555u;
    x ^= (x >> 2) & 0x33333333u;
    x ^= (x >> 4) & 0x0f0f0f0fu;
    x ^= (x >> 8) & 0x00ff00ffu;
    x ^= (x >> 16) & 0x0000ffffu;
    return x;
}

/// For k < n, the Sobol sampler's coordinates of one pair of dimensions for the sample with per-
/// pixel key keys[k] (sobol_pixel_key) and index indices[k]:
///   u0[k] = SampleStream::from_key(keys[k], indices[k], Sobol).get(dimension)
///   u1[k] = ... .get(dimension + 1)          (get2's pairs; u1 may be null for get alone)
/// `dimension` is coordinate 0 of its pair when u1 is given; alone, either coordinate.
void sobol_batch(const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t dimension, float* u0,
                 float* u1 = nullptr);

/// The same for either sampler: keys[k] is SampleStream::key of sample k (per pixel with Sobol,
/// per sample with the independent sampler), and
///   u0[k] = SampleStream::from_key(keys[k], indices[k], kind).get(dimension), u1 likewise get2's.
void sample_batch(SamplerKind kind, const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t dimension,
                  float* u0, float* u1 = nullptr);

/// bsdf_randoms (core/sampler.h) for a whole shade queue: for k < n,
///   lobe[k], dir0[k], dir1[k] = bsdf_randoms(SampleStream::from_key(keys[k], indices[k], kind), depth)
/// so the tracer's BSDF stage and path replay read one layout of the stage's dimensions.
void bsdf_randoms_batch(SamplerKind kind, const uint64_t* keys, const uint32_t* indices, size_t n, uint32_t depth,
                        float* lobe, float* dir0, float* dir1);

}  // namespace lpt
