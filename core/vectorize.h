// Batch loops over struct-of-arrays (cosine warp, light samples, camera rays) are written for
// GCC's auto-vectoriser and compiled twice on x86-64: the baseline (SSE2, 4 wide) and an AVX2
// clone (8 wide) that the loader picks on CPUs that have it. No FMA in the clone: fused
// rounding would make the batch differ from the scalar code it must equal. Elsewhere (other
// architectures, other compilers) the baseline build alone.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define LPT_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define LPT_VECTOR_CLONES
#endif
