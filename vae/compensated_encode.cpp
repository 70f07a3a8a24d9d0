#include "vae/compensated_encode.h"
#include <algorithm>
#include <stdexcept>
#include <string>

namespace lpt {

std::vector<float> block_mean(const std::vector<float>& image, int width, int height, int channels, int f) {
    if (f <= 0 || width % f || height % f || image.size() != size_t(width) * height * channels)
        throw std::invalid_argument("block_mean: a " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                                    std::to_string(channels) + " image of " + std::to_string(image.size()) +
                                    " values does not split into " + std::to_string(f) + "-pixel blocks");
    std::vector<float> out(image.size());
    std::vector<double> sum(channels);
    const double inv_n = 1.0 / (double(f) * f);
    for (int by = 0; by < height; by += f)
        for (int bx = 0; bx < width; bx += f) {
            std::fill(sum.begin(), sum.end(), 0.0);
            for (int y = by; y < by + f; ++y)
                for (int x = bx; x < bx + f; ++x)
                    for (int c = 0; c < channels; ++c) sum[c] += image[(size_t(y) * width + x) * channels + c];
            for (int y = by; y < by + f; ++y)
                for (int x = bx; x < bx + f; ++x)
                    for (int c = 0; c < channels; ++c)
                        out[(size_t(y) * width + x) * channels + c] = float(sum[c] * inv_n);
        }
    return out;
}

std::vector<float> encode_compensated(const Vae& vae, const std::vector<float>& rgb, int width, int height, int block) {
    const int f = vae.convention().downsample;
    const std::vector<float> roundtrip = vae.decode(vae.encode(rgb, width, height), width / f, height / f);
    std::vector<float> residual(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) residual[i] = rgb[i] - roundtrip[i];
    const std::vector<float> bias = block_mean(residual, width, height, 3, block > 0 ? block : f);
    std::vector<float> shifted(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) shifted[i] = rgb[i] + bias[i];
    return vae.encode(shifted, width, height);
}

}  // namespace lpt
