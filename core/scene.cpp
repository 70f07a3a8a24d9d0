#include "core/scene.h"
#include "core/error.h"
#include <pmmintrin.h>
#include <xmmintrin.h>
#include <mutex>

namespace lpt {

RTCDevice embree_device() {
    static RTCDevice device = [] {
        RTCDevice d = rtcNewDevice(nullptr);
        if (!d)
            throw std::runtime_error("Embree: cannot create device (error " +
                                     std::to_string(rtcGetDeviceError(nullptr)) + ")");
        return d;
    }();
    return device;
}

void set_ftz_daz() {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

Scene::Scene() = default;
Scene::~Scene() {
    if (m_rtc) rtcReleaseScene(m_rtc);
}
Scene::Scene(Scene&& o) noexcept { *this = std::move(o); }
Scene& Scene::operator=(Scene&& o) noexcept {
    if (this == &o) return *this;
    if (m_rtc) rtcReleaseScene(m_rtc);
    file = std::move(o.file);
    shapes = std::move(o.shapes);
    materials = std::move(o.materials);
    emitters = std::move(o.emitters);
    environment = o.environment;
    camera = o.camera;
    integrator = o.integrator;
    lights = std::move(o.lights);
    m_rtc = o.m_rtc;
    o.m_rtc = nullptr;
    m_center = o.m_center;
    m_radius = o.m_radius;
    return *this;
}

int Scene::find_shape(const std::string& id) const {
    for (size_t i = 0; i < shapes.size(); ++i)
        if (shapes[i].id == id) return int(i);
    return -1;
}

void Scene::build() {
    if (shapes.empty()) throw SceneError(file, "shapes", "scene has no shapes");
    for (size_t i = 0; i < shapes.size(); ++i) {
        const Shape& s = shapes[i];
        if (s.material < 0 || s.material >= int(materials.size()))
            throw SceneError(file, "shapes." + s.id + ".material", "shape has no valid material");
        if (s.emitter >= int(emitters.size()))
            throw SceneError(file, "shapes." + s.id + ".emitter", "bad emitter index");
    }
    for (auto& s : shapes) s.prepare();

    if (m_rtc) rtcReleaseScene(m_rtc);
    RTCDevice dev = embree_device();
    m_rtc = rtcNewScene(dev);
    rtcSetSceneBuildQuality(m_rtc, RTC_BUILD_QUALITY_HIGH);
    Eigen::AlignedBox3f box;
    for (size_t i = 0; i < shapes.size(); ++i) {
        const TriangleMesh& m = shapes[i].mesh;
        RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree reads vertex buffers with 16-byte loads: pad by one float.
        float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                               3 * sizeof(float), m.positions.size()));
        for (size_t k = 0; k < m.positions.size(); ++k) {
            v[3 * k] = m.positions[k].x();
            v[3 * k + 1] = m.positions[k].y();
            v[3 * k + 2] = m.positions[k].z();
            box.extend(m.positions[k]);
        }
        uint32_t* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                       3 * sizeof(uint32_t), m.triangle_count()));
        std::copy(m.indices.begin(), m.indices.end(), idx);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(m_rtc, g, unsigned(i));
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(m_rtc);
    if (RTCError err = rtcGetDeviceError(dev); err != RTC_ERROR_NONE)
        throw SceneError(file, "", "Embree failed to build the scene (error " + std::to_string(int(err)) + ")");
    m_center = box.center();
    m_radius = std::max(1e-3f, 0.5f * box.diagonal().norm());
    lights.build(emitters, shapes, integrator.light_sampling, m_radius);
}

SurfaceInteraction Scene::intersect(const Ray& ray) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh;
    rh.ray.org_x = ray.o.x();
    rh.ray.org_y = ray.o.y();
    rh.ray.org_z = ray.o.z();
    rh.ray.dir_x = ray.d.x();
    rh.ray.dir_y = ray.d.y();
    rh.ray.dir_z = ray.d.z();
    rh.ray.tnear = ray.tmin;
    rh.ray.tfar = ray.tmax;
    rh.ray.time = 0.f;
    rh.ray.mask = ~0u;
    rh.ray.flags = 0;
    rh.ray.id = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(m_rtc, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
    SurfaceInteraction si = shapes[rh.hit.geomID].interaction(rh.hit.primID, rh.hit.u, rh.hit.v, rh.ray.tfar);
    si.shape = int(rh.hit.geomID);
    return si;
}

bool Scene::occluded(const Vec3f& o, const Vec3f& d, float tmax) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    r.org_x = o.x();
    r.org_y = o.y();
    r.org_z = o.z();
    r.dir_x = d.x();
    r.dir_y = d.y();
    r.dir_z = d.z();
    r.tnear = 0.f;
    r.tfar = tmax;
    r.time = 0.f;
    r.mask = ~0u;
    r.flags = 0;
    r.id = 0;
    rtcOccluded1(m_rtc, &ctx, &r);
    return r.tfar < 0.f;
}

}  // namespace lpt
