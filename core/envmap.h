// Environment map ("envmap"): radiance from an equirectangular float image (Mitsuba 3's
// convention), rotated by to_world, times `scale`, importance sampled for next-event estimation.
//   local direction d = to_world⁻¹ ω;  u = atan2(d.x, −d.z) / 2π (mod 1),  v = acos(d.y) / π;
//   the texel is the one containing (u, v) (nearest, see below);
//   sampling picks a texel with probability ∝ luminance · sin θ_row (rows by their marginal,
//   then a column), then a uniform (u, v) inside it: pdf_Ω = p_texel · W · H / (2π² sin θ).
// Lookups are nearest-texel, not Mitsuba's bilinear: radiance is then exactly piecewise
// constant like the sampling density, so NEE alone is unbiased and a single bright texel is a
// sharp light of known solid angle (docs/sampling.md, "Environment map").
#pragma once
#include "core/emitter.h"
#include "core/texture.h"
#include "core/transform.h"
#include <memory>
#include <string>
#include <vector>

namespace lpt {

class EnvMap {
public:
    /// Reads `path` (any OpenImageIO format; float images are linear, 8-bit ones sRGB-decoded).
    /// Throws SceneError naming the file if it is missing or unreadable.
    static std::shared_ptr<const EnvMap> load(const std::string& path, const Transform& to_world, float scale);
    /// From linear RGB data (tests, generated maps).
    EnvMap(std::shared_ptr<const BitmapData> image, const Transform& to_world, float scale);

    /// Radiance arriving from world direction `w` (pointing away from the scene), RGB.
    Eigen::Array3f eval(const Vec3f& w) const;
    /// Luminance of eval(w) over the map's mean luminance: the direction-dependent factor a
    /// latent environment multiplies its learned vector by (1 for a constant map).
    float relative_luminance(const Vec3f& w) const;
    /// Direction toward the environment; pdf in solid angle (0 if the sample is degenerate).
    LightSample sample(const Vec2f& u) const;
    float pdf(const Vec3f& w) const;
    /// Mean radiance over the sphere of directions (for light selection by power).
    const Eigen::Array3f& mean_radiance() const { return m_mean; }
    const std::string& path() const { return m_image->path; }

private:
    int texel_of(const Vec3f& w, float* sin_theta) const;

    std::shared_ptr<const BitmapData> m_image;
    Eigen::Matrix3f m_to_world, m_to_local;
    float m_scale;
    Eigen::Array3f m_mean = Eigen::Array3f::Zero();
    float m_mean_luminance = 0.f;
    std::vector<float> m_texel_pmf;           ///< per texel, sums to 1
    std::vector<float> m_row_cdf, m_col_cdf;  ///< H + 1 entries; H × (W + 1) entries
};

}  // namespace lpt
