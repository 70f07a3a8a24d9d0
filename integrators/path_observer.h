// PathObserver: sees every scoring event of every path while the wavefront tracer runs. The
// path recorder (autodiff/path_record.h) is one: it keeps what does not depend on the learned
// coefficients, and the adjoint sweeps those records backwards (docs/path-replay.md). Hooks of one wavefront are called
// by one thread, in path order per slot: begin, then per depth [emission | ambient]* light_sample* bounce*, shadow*,
// then end.
#pragma once
#include "core/bsdf.h"
#include "core/spectrum.h"
#include <cstddef>
#include <cstdint>

namespace lpt {

template <int N>
class PathObserver {
public:
    virtual ~PathObserver() = default;
    /// A wavefront of `n` paths of image tile `tile` starts; slots are 0..n-1.
    virtual void begin(int tile, size_t n) = 0;
    // Hooks report only what does not depend on the spectra (the observer recomputes β and BSDF
    // values from its own coefficients: docs/path-replay.md (2)).
    /// Emission of `emitter` reached by BSDF sampling or escape, added as β · mis · L̃e.
    virtual void emission(uint32_t slot, int emitter, float mis) = 0;
    /// Ĩa: β · L̃a(shape) at the first non-delta vertex, or β · background (shape = -1).
    virtual void ambient(uint32_t slot, int shape) = 0;
    /// A light sample at a vertex of `shape`: NEE (if `nee`: β · f(wi, wo)·|cos| · L̃e ·
    /// w_over_pdf) and/or Ĩc's gate (if `first`). shadow_id indexes this depth's shadow rays, or
    /// is -1 when no ray was traced because V = 0 is known (attached shadow, no light).
    virtual void light_sample(uint32_t slot, int shadow_id, int shape, int emitter, float w_over_pdf,
                              const BSDFContext& ctx, const Vec3f& wi, const Vec3f& wo, bool nee, bool first) = 0;
    /// The shadow ray `shadow_id` of the current depth was blocked or not.
    virtual void shadow(int shadow_id, bool blocked) = 0;
    /// BSDF sampling at path depth `depth` continued the path from a vertex of `shape`:
    /// next β = β · bs.weight / q.
    virtual void bounce(uint32_t slot, int shape, const BSDFContext& ctx, const Vec3f& wi, const BSDFSample<N>& bs,
                        float q, int depth) = 0;
    /// The wavefront is done; path `slot` was sample sample[slot] of pixel pixel[slot].
    virtual void end(const uint32_t* pixel, const uint32_t* sample, size_t n) = 0;
};

}  // namespace lpt
