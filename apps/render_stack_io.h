// Reading renders to compare (`latentpt compare`, `latentpt bench --equal-noise`): EXR stacks
// box-averaged to a common size, and the mask of pixels that see an emitter directly.
#pragma once
#include "core/image_compare.h"
#include "core/scene.h"
#include <cstdint>
#include <string>
#include <vector>

namespace lpt::app {

/// RGB of an EXR, box-averaged by `factor` (a 1024² reference against a 256² render: factor 4,
/// the same pixel integrals for a box filter).
std::vector<float> load_rgb(const std::string& path, int factor, int& width, int& height);

/// Stack of renders; every file must have the size of the first after downsampling to
/// `target_width` (0: as they are).
RenderStack load_stack(const std::vector<std::string>& paths, int target_width);

/// 1 where a directly seen emitter (emitting shape, or the environment) covers any part of the
/// pixel's filter footprint: 4x4 rays per pixel, spread over the footprint.
std::vector<uint8_t> emitter_mask(const Scene& scene, int width, int height);

}  // namespace lpt::app
