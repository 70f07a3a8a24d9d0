// Scene: shapes (world-space triangle meshes), material descriptions, emitters, camera and
// integrator settings, plus the Embree BVH. Spectral data for a channel count N lives in
// SceneSpectra<N>, built from the descriptions here, so the RGB and latent renderers share
// geometry, sampling and ids.
#pragma once
#include "core/camera.h"
#include "core/emitter.h"
#include "core/light_sampler.h"
#include "core/props.h"
#include "core/sampler.h"
#include "core/shape.h"
#include <embree3/rtcore.h>
#include <string>
#include <vector>

namespace lpt {

struct IntegratorSettings {
    int max_depth = 8;                         ///< longest path in segments, Mitsuba's semantics; -1 = unbounded
    int rr_depth = 5;                          ///< Russian roulette from this depth on
    int spp = 16;                              ///< default samples per pixel
    SamplerKind sampler = SamplerKind::Sobol;  ///< docs/sampling.md
    LightSampling light_sampling = LightSampling::Power;
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(Scene&&) noexcept;
    Scene& operator=(Scene&&) noexcept;
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    std::string file;  ///< where it was loaded from (error messages)
    std::vector<Shape> shapes;
    std::vector<Props> materials;
    std::vector<Emitter> emitters;
    int environment = -1;  ///< index into emitters of the constant emitter, or -1
    Camera camera;
    IntegratorSettings integrator;
    LightSampler lights;

    /// Validates references, prepares shapes, builds the BVH and light sampler. Call again after
    /// any edit of shapes or emitters.
    void build();

    int find_shape(const std::string& id) const;  ///< -1 if absent
    RTCScene rtc() const { return m_rtc; }
    Vec3f bounds_center() const { return m_center; }
    float bounds_radius() const { return m_radius; }

    /// Scalar queries (tests, AOVs); the integrators use Embree's stream API directly.
    SurfaceInteraction intersect(const Ray& ray) const;
    bool occluded(const Vec3f& o, const Vec3f& d, float tmax) const;

private:
    RTCScene m_rtc = nullptr;
    Vec3f m_center = Vec3f::Zero();
    float m_radius = 1.f;
};

/// The process-wide Embree device (created on first use).
RTCDevice embree_device();
/// Embree wants flush-to-zero and denormals-are-zero in every thread that traces.
void set_ftz_daz();

}  // namespace lpt
