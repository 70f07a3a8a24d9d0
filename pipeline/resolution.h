// "WxH" resolutions as the command line and the pipeline's jobs spell them.
#pragma once
#include <string>

namespace lpt::pipeline {

/// Parses "WxH" (or "WXH") with positive integers into w, h; throws std::invalid_argument naming
/// `option` (e.g. "--res") and the text otherwise.
void parse_resolution(const std::string& text, int& w, int& h, const std::string& option);

}  // namespace lpt::pipeline
