// Where the shared data lives (weights, third-party scenes): LATENTPT_SHARED, else ../shared
// beside the source tree.
#pragma once
#include <string>

namespace lpt::pipeline {

std::string shared_dir();
/// `dir`, or the shared TAESD3 weights folder when `dir` is empty.
std::string default_vae_dir(const std::string& dir);
/// `dir`, or the shared LPIPS weights folder when `dir` is empty.
std::string default_lpips_dir(const std::string& dir);

}  // namespace lpt::pipeline
