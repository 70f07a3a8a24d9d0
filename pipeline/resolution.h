// "WxH" resolutions and "A:B:S" frame ranges as the command line and the pipeline's jobs spell
// them.
#pragma once
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace lpt::pipeline {

/// Parses "WxH" (or "WXH") with positive integers into w, h; throws std::invalid_argument naming
/// `option` (e.g. "--res") and the text otherwise.
void parse_resolution(const std::string& text, int& w, int& h, const std::string& option);

/// The non-negative decimal integers of `text` separated by `sep` ("0:40:20" → {0, 40, 20}), or
/// nothing when a piece is empty, not all digits, or beyond int: "8x8junk" and "4294967304x8"
/// are errors, not 8x8 (sscanf's %d stopped at the junk and wrapped the overflow).
std::optional<std::vector<int>> split_integers(const std::string& text, char sep);

/// check_image_fits (core/film.h) for a size that `option` gave ("--res"): its std::length_error
/// becomes std::invalid_argument naming the option, before any work is done.
void check_size_fits(int w, int h, size_t floats_per_pixel, const std::string& option);

}  // namespace lpt::pipeline
