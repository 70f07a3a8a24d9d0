// Structure-of-arrays state for one wavefront of paths. Ray arrays are laid out exactly as
// Embree 3's rtcIntersectNp / rtcOccludedNp read them (one 16-byte-aligned array per
// component), so tracing needs no repacking. Per-path spectra sit contiguously per path
// (N floats; 16 = two AVX2 registers), scalars in their own arrays.
#pragma once
#include "core/geometry.h"
#include "core/spectrum.h"
#include <embree3/rtcore.h>
#include <cstdint>
#include <vector>

namespace lpt {

template <typename T>
using AlignedVector = std::vector<T, Eigen::aligned_allocator<T>>;

/// Rays + hits for rtcIntersectNp (hits unused by rtcOccludedNp).
struct RayArrays {
    AlignedVector<float> ox, oy, oz, tnear, dx, dy, dz, time, tfar;
    AlignedVector<unsigned> mask, id, flags;
    AlignedVector<float> ngx, ngy, ngz, u, v;
    AlignedVector<unsigned> prim, geom, inst;
    size_t size = 0;

    void reserve(size_t n);
    void clear() { size = 0; }
    /// Appends a ray; returns its index.
    size_t push(const Vec3f& o, const Vec3f& d, float tmin, float tmax);
    /// n rays whose origins, directions and t ranges the caller writes in place (camera rays).
    void resize_for_fill(size_t n);
    Vec3f origin(size_t i) const { return Vec3f(ox[i], oy[i], oz[i]); }
    Vec3f direction(size_t i) const { return Vec3f(dx[i], dy[i], dz[i]); }
    bool hit(size_t i) const { return geom[i] != RTC_INVALID_GEOMETRY_ID; }
    bool blocked(size_t i) const { return tfar[i] < 0.f; }  ///< rtcOccludedNp's answer

    void intersect(RTCScene scene, bool coherent);
    void occluded(RTCScene scene);
};

/// Per-path state of a wavefront. Slot k is fixed for a path's lifetime; `queue` lists the live
/// slots in the order of the current RayArrays.
template <int N>
struct PathState {
    AlignedVector<Spectrum<N>> beta;                ///< throughput (signed for latents)
    AlignedVector<Spectrum<N>> radiance;            ///< accumulated estimate
    std::vector<uint32_t> pixel, sample;            ///< film pixel and sample index
    std::vector<uint64_t> key;                      ///< SampleStream key of (seed, pixel, sample), hashed once
    std::vector<float> prev_pdf;                    ///< solid-angle pdf of the last BSDF sample (MIS)
    std::vector<uint8_t> prev_delta;                ///< last scattering was a delta lobe (or camera)
    AlignedVector<Vec3f> prev_p;                    ///< last vertex position (area-light pdf on hits)
    AlignedVector<Spectrum<N>> ambient, occlusion;  ///< latent Ĩa (+ background) and Ĩc
    std::vector<uint8_t> past_first;                ///< the first non-delta vertex is behind us (latent)

    void resize(size_t n) {
        beta.resize(n);
        radiance.resize(n);
        pixel.resize(n);
        sample.resize(n);
        key.resize(n);
        prev_pdf.resize(n);
        prev_delta.resize(n);
        prev_p.resize(n);
        ambient.resize(n);
        occlusion.resize(n);
        past_first.resize(n);
    }
};

/// Surface vertices waiting to be shaded (NEE, then BSDF sampling), in queue order. Arrays keep
/// their capacity across depths; `count` entries are live.
struct ShadeQueue {
    std::vector<uint32_t> slot;
    std::vector<uint64_t> key;     ///< its path's sample key and index, side by side for
    std::vector<uint32_t> sample;  ///< sample_batch (core/sample_batch.h)
    std::vector<int> shape;
    AlignedVector<Vec3f> p, ng, wi;  ///< wi in the local shading frame
    std::vector<Frame> frame;
    AlignedVector<Vec2f> uv;
    std::vector<uint8_t> flags;  ///< kContinue: NEE + BSDF sampling; kFirst: latent Ĩc gate here
    static constexpr uint8_t kContinue = 1, kFirst = 2;
    size_t count = 0;
    void reset(size_t capacity) {
        count = 0;
        if (slot.size() >= capacity) return;
        slot.resize(capacity);
        key.resize(capacity);
        sample.resize(capacity);
        shape.resize(capacity);
        p.resize(capacity);
        ng.resize(capacity);
        wi.resize(capacity);
        frame.resize(capacity);
        uv.resize(capacity);
        flags.resize(capacity);
    }
    size_t size() const { return count; }
};

/// Shadow rays of next-event estimation with the contribution each delivers if unblocked.
template <int N>
struct ShadowQueue {
    RayArrays rays;
    std::vector<uint32_t> slot;
    AlignedVector<Spectrum<N>> contribution;  ///< NEE: added if unblocked
    AlignedVector<Spectrum<N>> occlusion;     ///< latent β·L̃c: added if the gate opens (else empty)
    void clear() {
        rays.clear();
        slot.clear();
        contribution.clear();
        occlusion.clear();
    }
};

}  // namespace lpt
