#include "integrators/wavefront_state.h"
#include <algorithm>

namespace lpt {

void RayArrays::reserve(size_t n) {
    size_t old = ox.size();
    for (auto* a : {&ox, &oy, &oz, &tnear, &dx, &dy, &dz, &tfar, &ngx, &ngy, &ngz, &u, &v}) a->resize(n);
    for (auto* a : {&prim, &geom, &inst}) a->resize(n);
    // Fields no stage changes are written once here instead of per ray.
    time.resize(n, 0.f);
    mask.resize(n, ~0u);
    flags.resize(n, 0u);
    id.resize(n);
    for (size_t i = old; i < n; ++i) id[i] = unsigned(i);
}

size_t RayArrays::push(const Vec3f& o, const Vec3f& d, float tmin, float tmax) {
    if (size == ox.size()) reserve(size ? 2 * size : 1024);
    size_t i = size++;
    ox[i] = o.x();
    oy[i] = o.y();
    oz[i] = o.z();
    dx[i] = d.x();
    dy[i] = d.y();
    dz[i] = d.z();
    tnear[i] = tmin;
    tfar[i] = tmax;
    geom[i] = RTC_INVALID_GEOMETRY_ID;  // Embree leaves it untouched on a miss
    return i;
}

void RayArrays::resize_for_fill(size_t n) {
    if (ox.size() < n) reserve(n);
    size = n;
    std::fill(geom.begin(), geom.begin() + n, RTC_INVALID_GEOMETRY_ID);
}

void RayArrays::intersect(RTCScene scene, bool coherent) {
    if (!size) return;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    RTCRayHitNp rh;
    rh.ray = {ox.data(), oy.data(),   oz.data(),   tnear.data(), dx.data(), dy.data(),
              dz.data(), time.data(), tfar.data(), mask.data(),  id.data(), flags.data()};
    rh.hit.Ng_x = ngx.data();
    rh.hit.Ng_y = ngy.data();
    rh.hit.Ng_z = ngz.data();
    rh.hit.u = u.data();
    rh.hit.v = v.data();
    rh.hit.primID = prim.data();
    rh.hit.geomID = geom.data();
    rh.hit.instID[0] = inst.data();
    rtcIntersectNp(scene, &ctx, &rh, unsigned(size));
}

void RayArrays::occluded(RTCScene scene) {
    if (!size) return;
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    RTCRayNp r = {ox.data(), oy.data(),   oz.data(),   tnear.data(), dx.data(), dy.data(),
                  dz.data(), time.data(), tfar.data(), mask.data(),  id.data(), flags.data()};
    rtcOccludedNp(scene, &ctx, &r, unsigned(size));
}

}  // namespace lpt
