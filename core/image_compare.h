// Comparing two renders of one scene for bias, with each side's Monte Carlo noise estimated so
// that noise is not called bias (docs/validation.md (1)-(4)).
//
// Each side is a stack of K >= 1 renders of the same scene with independent seeds. The side's
// estimate is their mean; with K >= 2 the variance of that mean is estimated per pixel from the
// spread of the K renders, and a block mean's variance is the sum of its pixels' variances over
// n² (pixels are independent under per-pixel seeding). With K = 1 that side's noise is unknown and
// counted as zero, which the result says.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace lpt {

/// K renders (interleaved RGB, row-major, same size) of one scene with independent seeds.
struct RenderStack {
    int width = 0, height = 0;
    std::vector<std::vector<float>> renders;
};

struct BlockComparison {
    int x0 = 0, y0 = 0, width = 0, height = 0;  ///< pixel rectangle
    int pixels = 0;                             ///< unmasked pixels used
    double test_mean = 0, ref_mean = 0;         ///< mean over unmasked pixels of (R + G + B) / 3
    double ratio = 1, sigma = 0;                ///< test / ref and its 1σ noise
    double z = 0;                               ///< (ratio − 1) / sigma; 0 when sigma is 0
    bool flagged = false;                       ///< |z| > threshold
};

struct ImageComparison {
    std::array<double, 3> test_mean{}, ref_mean{}, mean_ratio{}, mean_ratio_sigma{};  ///< unmasked pixels
    double rel_mse = 0;  ///< mean over unmasked pixels and channels of (t − r)² / (r² + 0.01)
    int masked_pixels = 0;
    bool test_noise_known = false, ref_noise_known = false;
    int block_size = 32;
    int blocks_x = 0, blocks_y = 0;
    std::vector<BlockComparison> blocks;  ///< row-major; blocks with no unmasked pixel have pixels = 0
    int flagged = 0;
    double z_threshold = 3;
};

/// Compares `test` against `ref` in blocks of block_size² pixels. `emitter_mask` (width·height,
/// nonzero = leave out) removes directly seen emitters, whose huge values would otherwise dominate
/// means and ratios through filter differences at their edges; empty = no mask. Throws
/// std::invalid_argument for mismatched sizes or empty stacks.
ImageComparison compare_renders(const RenderStack& test, const RenderStack& ref,
                                const std::vector<uint8_t>& emitter_mask, int block_size = 32,
                                double z_threshold = 3.0);

/// A plain-text table of the comparison: means, ratios with their noise, relMSE, flagged blocks.
std::string format_comparison(const ImageComparison& c, const std::string& test_name, const std::string& ref_name);

/// Colour-coded map of the block ratios (width·height RGB display values in [0, 1]): white at
/// ratio 1, red where test is brighter, blue where darker, saturating at ±range; flagged blocks
/// get a black outline.
std::vector<float> ratio_map(const ImageComparison& c, int width, int height, double range = 0.1);

}  // namespace lpt
