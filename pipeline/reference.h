// The paper's target: the scene path traced in RGB, display-mapped, encoded by the VAE.
#pragma once
#include "pipeline/progress.h"
#include <string>
#include <vector>

namespace lpt {
class Scene;
class Vae;
}  // namespace lpt

namespace lpt::pipeline {

/// The paper's display mapping for references: clip to [0, 1] (or |x|/(1+|x|) for "reinhard"),
/// then x^(1/2.2).
float display_value(float v, const std::string& tone);

/// Path-traced RGB of `scene` at width x height and `spp` (seed 0x5eed), display-mapped with
/// `tone`, encoded by `vae`. `save_png` (if not empty) receives the display image, `display_rgb`
/// (if given) its values. Throws if the size is not a multiple of the VAE's downsampling.
std::vector<float> encoded_reference_of(const Scene& scene, int width, int height, int spp, const std::string& tone,
                                        const Vae& vae, const std::string& save_png,
                                        std::vector<float>* display_rgb = nullptr, const Reporter& report = {});

/// The cache name of a view's training reference ("training_<W>x<H>_<spp>spp_<tone>"): fits
/// and the unedited frames of edit sequences share it.
std::string training_reference_key(int width, int height, int spp, const std::string& tone);

/// encoded_reference_of through a cache: `cache_stem`.exr holds the display RGB and
/// `cache_stem`_latent.exr its encoding. A cached reference is read (and re-encoded only when its
/// latent file is missing); a missing one is traced and both files written, latent first, each
/// atomically, so several jobs (an experiment's fits and edit sequences) trace a reference once
/// and encode it once. An empty `cache_stem` caches nothing. `display_rgb` receives the display
/// image and `save_png` (if not empty) a picture of it.
std::vector<float> cached_encoded_reference(const Scene& scene, int width, int height, int spp, const std::string& tone,
                                            const Vae& vae, const std::string& cache_stem, const std::string& save_png,
                                            std::vector<float>& display_rgb, const Reporter& report = {});

}  // namespace lpt::pipeline
