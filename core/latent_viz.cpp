#include "core/latent_viz.h"
#include <algorithm>
#include <cmath>

namespace lpt {

Image latent_grid(const float* data, int width, int height, int channels, float scale) {
    const int cols = int(std::ceil(std::sqrt(double(channels))));
    const int rows = (channels + cols - 1) / cols;
    if (scale <= 0.f) {
        for (size_t i = 0; i < size_t(width) * height * channels; ++i)
            if (std::isfinite(data[i])) scale = std::max(scale, std::abs(data[i]));
        if (scale <= 0.f) scale = 1.f;
    }
    Image img;
    img.width = cols * (width + 1) - 1;
    img.height = rows * (height + 1) - 1;
    img.channels = 3;
    img.data.assign(size_t(img.width) * img.height * 3, 0.25f);  // gaps in grey
    for (int c = 0; c < channels; ++c) {
        const int ox = (c % cols) * (width + 1), oy = (c / cols) * (height + 1);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                float v = data[(size_t(y) * width + x) * channels + c] / scale;
                float* px = &img.data[(size_t(oy + y) * img.width + ox + x) * 3];
                px[0] = v < 0.f ? std::min(-v, 1.f) : 0.f;
                px[1] = v > 0.f ? std::min(v, 1.f) : 0.f;
                px[2] = 0.f;
            }
    }
    return img;
}

}  // namespace lpt
