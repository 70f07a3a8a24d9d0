// The batched samplers (core/sample_batch.h) give the bits of the one-sample form
// (core/sampler.h) that the tracer used before, so images and path replay do not change: the
// table-free dimension-1 map against the table on every unit vector (both are linear over GF(2),
// so that is every word), and whole batches against SampleStream::get / get2 in every dimension
// of the layout, with lengths that leave a vector tail.
#include "core/sample_batch.h"
#include "core/sampler.h"
#include <gtest/gtest.h>
#include <random>
#include <stdexcept>
#include <vector>

using namespace lpt;

TEST(SampleBatch, SobolDimensionOneMapEqualsTheTableOnEveryUnitVector) {
    for (int k = 0; k < 32; ++k) {
        const uint32_t e = 1u << k;
        EXPECT_EQ(reverse_bits32(sobol_dimension1_unreversed(e)), sobol_dimension1(e)) << k;
        EXPECT_EQ(sobol_dimension1_unreversed(reverse_bits32(e)), kSobolDimension1Reversed(e)) << k;
    }
    std::mt19937 rng(3);
    for (int i = 0; i < 1000; ++i) {  // linearity, spot-checked
        const uint32_t x = rng();
        EXPECT_EQ(reverse_bits32(sobol_dimension1_unreversed(x)), sobol_dimension1(x)) << x;
    }
}

TEST(SampleBatch, EqualsTheOneSampleFormInEveryDimension) {
    std::mt19937_64 rng(11);
    for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent})
        for (size_t n : {size_t(1), size_t(7), size_t(1003)}) {
            std::vector<uint64_t> keys(n);
            std::vector<uint32_t> indices(n);
            for (size_t k = 0; k < n; ++k) {
                indices[k] = k % 3 == 0 ? uint32_t(k) : uint32_t(rng());  // small indices and any 32 bits
                keys[k] = SampleStream(rng(), uint32_t(rng()), indices[k], kind).key;
            }
            const auto one = [&](size_t k) { return SampleStream::from_key(keys[k], indices[k], kind); };
            for (uint32_t dimension = 0; dimension < dim::bounce(4, 0); ++dimension) {
                std::vector<float> u(n, -1.f);
                sample_batch(kind, keys.data(), indices.data(), n, dimension, u.data());
                for (size_t k = 0; k < n; ++k)
                    ASSERT_EQ(u[k], one(k).get(dimension))
                        << "dimension " << dimension << ", sample " << k << " of " << n;
                const DimensionPair d = dimension_pair(dimension);
                if (d.coordinate != 0 || dimension_pair(dimension + 1).pair != d.pair) continue;
                std::vector<float> u0(n, -1.f), u1(n, -1.f);
                sample_batch(kind, keys.data(), indices.data(), n, dimension, u0.data(), u1.data());
                for (size_t k = 0; k < n; ++k) {
                    float e0, e1;
                    one(k).get2(dimension, e0, e1);
                    ASSERT_EQ(u0[k], e0) << "dimension " << dimension << ", sample " << k;
                    ASSERT_EQ(u1[k], e1) << "dimension " << dimension + 1 << ", sample " << k;
                }
            }
        }
}

// The light choice and the light position are different pairs: asking for them as one is a
// programming error, not two numbers of different pairs.
TEST(SampleBatch, BothCoordinatesOnlyOfOnePair) {
    const uint64_t key = sobol_pixel_key(1, 2);
    const uint32_t index = 3;
    float u0 = -1.f, u1 = -1.f;
    EXPECT_THROW(sobol_batch(&key, &index, 1, dim::bounce(0, dim::kLightChoice), &u0, &u1), std::logic_error);
    EXPECT_EQ(u0, -1.f);
}

// The tracer's BSDF stage draws bsdf_randoms_batch; path replay re-samples delta lobes from
// bsdf_randoms: both must read the stage's dimensions in one layout.
TEST(SampleBatch, BsdfRandomsBatchEqualsTheOneSampleForm) {
    std::mt19937_64 rng(5);
    const size_t n = 37;
    for (const SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Independent})
        for (uint32_t depth = 0; depth < 4; ++depth) {
            std::vector<uint64_t> keys(n);
            std::vector<uint32_t> indices(n);
            for (size_t k = 0; k < n; ++k) {
                indices[k] = uint32_t(rng());
                keys[k] = SampleStream(rng(), uint32_t(rng()), indices[k], kind).key;
            }
            std::vector<float> lobe(n, -1.f), dir0(n, -1.f), dir1(n, -1.f);
            bsdf_randoms_batch(kind, keys.data(), indices.data(), n, depth, lobe.data(), dir0.data(), dir1.data());
            for (size_t k = 0; k < n; ++k) {
                const BsdfRandoms u = bsdf_randoms(SampleStream::from_key(keys[k], indices[k], kind), depth);
                ASSERT_EQ(lobe[k], u.lobe) << "depth " << depth << ", sample " << k;
                ASSERT_EQ(dir0[k], u.dir[0]) << "depth " << depth << ", sample " << k;
                ASSERT_EQ(dir1[k], u.dir[1]) << "depth " << depth << ", sample " << k;
            }
        }
}
