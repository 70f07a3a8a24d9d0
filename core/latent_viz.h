// Pictures of multi-channel latents in the paper's colour code: each channel is a tile of a
// grid, green for positive values, red for negative, black at zero.
#pragma once
#include "core/image_io.h"

namespace lpt {

/// Grid of `channels` tiles (ceil(sqrt) columns, 1-pixel gaps), each pixel v mapped to
/// green = v / scale (v > 0) or red = -v / scale (v < 0). scale <= 0: the largest |v|.
Image latent_grid(const float* data, int width, int height, int channels, float scale = 0.f);

}  // namespace lpt
