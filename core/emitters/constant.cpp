// Constant environment emitter ("constant", key radiance: rgb): the same radiance from every
// direction of the sphere; sampled uniformly in solid angle.
#include "core/emitter.h"
#include "core/warp.h"

namespace lpt {

LightSample sample_constant_light(const Vec2f& u) {
    LightSample ls;
    ls.wi = sample_uniform_sphere(u);
    ls.n = -ls.wi;
    ls.pdf = pdf_uniform_sphere(ls.wi);
    return ls;
}

float pdf_constant_light() { return 0.25f * kInvPi; }

}  // namespace lpt
