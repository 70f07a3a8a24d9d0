// Environment map emitter: lookups, the luminance × sin θ sampling tables, and their pdf
// (core/envmap.h, docs/sampling.md "Environment map").
#include "core/envmap.h"
#include "core/error.h"
#include "core/spectrum.h"
#include <algorithm>
#include <cmath>

namespace lpt {

namespace {

float lum(const Eigen::Array3f& c) { return luminance(c); }

/// Index of the CDF interval containing u (cdf[0] = 0, cdf[n] = 1), skipping empty intervals.
int find_interval(const float* cdf, int n, float u) {
    int i = int(std::upper_bound(cdf, cdf + n + 1, u) - cdf) - 1;
    i = std::clamp(i, 0, n - 1);
    while (i > 0 && cdf[i + 1] - cdf[i] <= 0.f) --i;
    while (i < n - 1 && cdf[i + 1] - cdf[i] <= 0.f) ++i;
    return i;
}

}  // namespace

std::shared_ptr<const EnvMap> EnvMap::load(const std::string& path, const Transform& to_world, float scale) {
    Texture t = Texture::load_bitmap(path, false, TextureFilter::Nearest, TextureWrap::Repeat);
    return std::make_shared<EnvMap>(t.bitmap(), to_world, scale);
}

EnvMap::EnvMap(std::shared_ptr<const BitmapData> image, const Transform& to_world, float scale)
    : m_image(std::move(image)), m_scale(scale) {
    m_to_world = to_world.m.block<3, 3>(0, 0);
    m_to_local = m_to_world.inverse();
    const int w = m_image->width, h = m_image->height;
    m_texel_pmf.assign(size_t(w) * h, 0.f);
    m_row_cdf.assign(size_t(h) + 1, 0.f);
    m_col_cdf.assign(size_t(h) * (w + 1), 0.f);
    // Solid angle of a texel in row j: (2π / W) (cos θ_j − cos θ_{j+1}); its sampling weight uses
    // sin θ at the row centre, matching the pdf's 1/sin θ inside the texel to first order.
    double total = 0, mean_rgb[3] = {0, 0, 0};
    std::vector<double> row(h, 0.0);
    for (int j = 0; j < h; ++j) {
        const double t0 = kPi * j / h, t1 = kPi * (j + 1) / h;
        const double d_omega = 2.0 * kPi / w * (std::cos(t0) - std::cos(t1));
        const float s = float(std::sin(kPi * (j + 0.5) / h));
        for (int i = 0; i < w; ++i) {
            const Eigen::Array3f c = m_image->pixel(i, j) * scale;
            for (int k = 0; k < 3; ++k) mean_rgb[k] += c[k] * d_omega;
            const float weight = std::max(lum(c), 0.f) * s;
            m_texel_pmf[size_t(j) * w + i] = weight;
            row[j] += weight;
        }
        total += row[j];
    }
    m_mean =
        Eigen::Array3f(float(mean_rgb[0] / (4 * kPi)), float(mean_rgb[1] / (4 * kPi)), float(mean_rgb[2] / (4 * kPi)));
    m_mean_luminance = lum(m_mean);
    if (!(total > 0.0)) return;  // black map: pdf 0 everywhere, sample() fails, emission 0
    double acc = 0;
    for (int j = 0; j < h; ++j) {
        double racc = 0;
        for (int i = 0; i < w; ++i) {
            racc += m_texel_pmf[size_t(j) * w + i];
            m_col_cdf[size_t(j) * (w + 1) + i + 1] = row[j] > 0 ? float(racc / row[j]) : float(i + 1) / w;
            m_texel_pmf[size_t(j) * w + i] = float(m_texel_pmf[size_t(j) * w + i] / total);
        }
        m_col_cdf[size_t(j) * (w + 1) + w] = 1.f;
        acc += row[j];
        m_row_cdf[j + 1] = float(acc / total);
    }
    m_row_cdf[h] = 1.f;
}

int EnvMap::texel_of(const Vec3f& w_world, float* sin_theta) const {
    const Vec3f d = m_to_local * w_world;
    // θ from atan2(ρ, y) and sin θ = ρ / |d|, not acos(y) and sqrt(1 − y²): those lose all
    // precision near the poles, where the pdf's 1/sin θ magnifies it.
    const float rho = std::sqrt(d.x() * d.x() + d.z() * d.z());
    float u = std::atan2(d.x(), -d.z()) * (0.5f * kInvPi);
    u -= std::floor(u);
    const float v = std::atan2(rho, d.y()) * kInvPi;
    const int w = m_image->width, h = m_image->height;
    const int i = std::clamp(int(u * w), 0, w - 1), j = std::clamp(int(v * h), 0, h - 1);
    if (sin_theta) *sin_theta = rho / d.norm();
    return j * w + i;
}

Eigen::Array3f EnvMap::eval(const Vec3f& w) const {
    const int t = texel_of(w, nullptr);
    return m_image->pixel(t % m_image->width, t / m_image->width) * m_scale;
}

float EnvMap::relative_luminance(const Vec3f& w) const {
    return m_mean_luminance > 0.f ? lum(eval(w)) / m_mean_luminance : 0.f;
}

float EnvMap::pdf(const Vec3f& w) const {
    float s = 0.f;
    const int t = texel_of(w, &s);
    if (!(s > 0.f)) return 0.f;
    return m_texel_pmf[t] * float(m_image->width) * float(m_image->height) / (2.f * kPi * kPi * s);
}

LightSample EnvMap::sample(const Vec2f& u) const {
    LightSample ls;
    const int w = m_image->width, h = m_image->height;
    if (!(m_row_cdf[h] > 0.f)) return ls;
    const int j = find_interval(m_row_cdf.data(), h, u.y());
    const float fv = (u.y() - m_row_cdf[j]) / std::max(m_row_cdf[j + 1] - m_row_cdf[j], 1e-30f);
    const float* cc = &m_col_cdf[size_t(j) * (w + 1)];
    const int i = find_interval(cc, w, u.x());
    const float fu = (u.x() - cc[i]) / std::max(cc[i + 1] - cc[i], 1e-30f);
    const float uu = (float(i) + std::clamp(fu, 0.f, 0x1.fffffep-1f)) / float(w);
    const float vv = (float(j) + std::clamp(fv, 0.f, 0x1.fffffep-1f)) / float(h);
    const float theta = vv * kPi, phi = uu * 2.f * kPi;
    const float st = std::sin(theta);
    if (!(st > 0.f)) return ls;
    const Vec3f d(std::sin(phi) * st, std::cos(theta), -std::cos(phi) * st);
    ls.wi = (m_to_world * d).normalized();
    ls.n = -ls.wi;
    ls.pdf = m_texel_pmf[size_t(j) * w + i] * float(w) * float(h) / (2.f * kPi * kPi * st);
    return ls;
}

}  // namespace lpt
