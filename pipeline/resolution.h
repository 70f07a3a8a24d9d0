// "WxH" resolutions and "A:B:S" frame ranges as the command line and the pipeline's jobs spell
// them.
#pragma once
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

}  // namespace lpt::pipeline
