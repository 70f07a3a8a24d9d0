// Chooses one emitter for next-event estimation. Probabilities come from the scene file's RGB
// description (never from learned latent values), so the latent renderer samples exactly as
// the RGB one does.
#pragma once
#include "core/emitter.h"
#include <vector>

namespace lpt {

enum class LightSampling { Uniform, Area, Power };

class LightSampler {
public:
    /// scene_radius: bounding-sphere radius, used to weigh the environment against area lights.
    void build(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, LightSampling mode, float scene_radius);
    bool empty() const { return m_pmf.empty(); }
    float pmf(int emitter) const { return m_pmf[emitter]; }
    /// Picks an emitter with u in [0,1); u_reuse gets the rescaled remainder for further use.
    int choose(float u, float* u_reuse) const;
    /// Light choice + position; pdf in solid angle including the choice probability.
    LightSample sample(const std::vector<Emitter>& emitters, const std::vector<Shape>& shapes, const Vec3f& ref,
                       float u_choice, const Vec2f& u_pos) const;

private:
    std::vector<float> m_pmf, m_cdf;
};

}  // namespace lpt
