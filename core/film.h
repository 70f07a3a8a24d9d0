// Film<N>: per-pixel sums of N-channel samples and their weights. Filter importance sampling
// (core/camera.h) means every sample belongs to exactly one pixel, so a pixel is only ever
// written by the one task that owns it and develop() is deterministic.
#pragma once
#include "core/spectrum.h"
#include <vector>

namespace lpt {

/// Throws std::length_error naming the size and the bytes it would need when a width x height
/// image of `floats_per_pixel` floats (its film and its developed copy) cannot fit in this
/// machine's memory, or when a side is not positive: a clear error instead of std::bad_alloc.
void check_image_fits(int width, int height, size_t floats_per_pixel);

template <int N>
class Film {
public:
    Film(int width, int height)
        : m_width((check_image_fits(width, height, 2 * N + 1), width)),
          m_height(height),
          m_sum(size_t(width) * height, Spectrum<N>::Zero()),
          m_weight(size_t(width) * height, 0.f) {}
    int width() const { return m_width; }
    int height() const { return m_height; }
    void add_sample(int pixel, const Spectrum<N>& value, float weight = 1.f) {
        m_sum[pixel] += weight * value;
        m_weight[pixel] += weight;
    }
    /// Interleaved N floats per pixel, row-major from the top-left; pixels with no weight are 0.
    std::vector<float> develop() const {
        std::vector<float> out(size_t(m_width) * m_height * N, 0.f);
        for (size_t i = 0; i < m_sum.size(); ++i)
            if (m_weight[i] != 0.f)
                for (int c = 0; c < N; ++c) out[i * N + c] = m_sum[i][c] / m_weight[i];
        return out;
    }

private:
    int m_width, m_height;
    std::vector<Spectrum<N>, Eigen::aligned_allocator<Spectrum<N>>> m_sum;
    std::vector<float> m_weight;
};

}  // namespace lpt
