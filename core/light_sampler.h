// Chooses one emitter for next-event estimation. Probabilities come from the scene file's RGB
// description (never from learned latent values), so the latent renderer samples exactly as
// the RGB one does.
#pragma once
#include "core/emitter.h"
#include <vector>

namespace lpt {

enum class LightSampling { Uniform, Area, Power };

struct LightBatch;

class LightSampler {
public:
    /// scene_radius: bounding-sphere radius, used to weigh the environment against area lights.
    void build(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, LightSampling mode,
               float scene_radius);
    bool empty() const { return m_pmf.empty(); }
    float pmf(int emitter) const { return m_pmf[emitter]; }
    /// Picks an emitter with u in [0,1); u_reuse gets the rescaled remainder for further use.
    int choose(float u, float* u_reuse) const;
    /// Light choice + position; pdf in solid angle including the choice probability.
    LightSample sample(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, const Vec3f& ref,
                       float u_choice, const Vec2f& u_pos) const;

    /// sample() for n reference points at once (struct of arrays in LightBatch): the choices
    /// one by one, then the geometry (barycentric square root, direction, distance, pdf) in a
    /// loop the compiler evaluates 4-8 wide. Environment lights and emitters with interpolated
    /// normals fall back to sample(). tests/integrators/test_lights_camera.cpp compares them.
    void sample_batch(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, size_t n,
                      LightBatch& batch) const;

private:
    std::vector<float> m_pmf, m_cdf;
};

/// Inputs (reference point, random numbers) and results of LightSampler::sample_batch, one
/// array per component. Fill rx..u_pos1 for entries [0, n); get(k) is sample()'s result.
struct LightBatch {
    std::vector<float> rx, ry, rz, u_choice, u_pos0, u_pos1;
    // Results, and the chosen triangle's corners and normal (scratch of the geometry pass).
    std::vector<float> px, py, pz, nx, ny, nz, wx, wy, wz, dist, pdf;
    std::vector<float> ax, ay, az, bx, by, bz, cx, cy, cz, pdf_area;
    std::vector<int> emitter;
    std::vector<uint8_t> scalar;  ///< 1: filled by sample() (environment, interpolated normals)
    void resize(size_t n);
    void set(size_t k, const LightSample& ls) {
        px[k] = ls.p.x();
        py[k] = ls.p.y();
        pz[k] = ls.p.z();
        nx[k] = ls.n.x();
        ny[k] = ls.n.y();
        nz[k] = ls.n.z();
        wx[k] = ls.wi.x();
        wy[k] = ls.wi.y();
        wz[k] = ls.wi.z();
        dist[k] = ls.dist;
        pdf[k] = ls.pdf;
        emitter[k] = ls.emitter;
    }
    LightSample get(size_t k) const {
        LightSample ls;
        ls.p = Vec3f(px[k], py[k], pz[k]);
        ls.n = Vec3f(nx[k], ny[k], nz[k]);
        ls.wi = Vec3f(wx[k], wy[k], wz[k]);
        ls.dist = dist[k];
        ls.pdf = pdf[k];
        ls.emitter = emitter[k];
        return ls;
    }
};

}  // namespace lpt
