// The emitter refiner (`refine --emitters`, docs/refiner.md "Emitter refiner"): a second, small
// refiner trained with film shifts, whose output replaces the main refiner's on the latent pixels
// where an emitter is seen otherwise than in the training view, and those around them. The
// training view shows each edge of a luminaire at one phase against the 8 × 8 grid of latent
// cells, which the main refiner learns; a moved camera or light puts the edge at another phase,
// where the main refiner blurs it. The film-shifted views show four phases.
#pragma once
#include "refiner/refiner.h"
#include <string>
#include <vector>

namespace lpt {
class Scene;
}

namespace lpt::pipeline {

/// The emitter refiner's files in a fit folder, beside refiner.pt's (its checkpoint's settings
/// in refiner_emitters_checkpoint.json).
inline const char* const kEmitterRefinerFile = "refiner_emitters.pt";
inline const char* const kEmitterRefinerCheckpoint = "refiner_emitters_checkpoint.pt";
inline const char* const kEmitterRefinerLoss = "refiner_emitters_loss.csv";
/// Sub-cells per side in which the mask compares a pixel's emitter coverage with training's.
constexpr int kEmitterMaskCells = 4;
/// Latent pixels around a changed one that take the emitter refiner's output too: the main
/// refiner's blurred edge and its halo reach two pixels out (docs/results.md "The luminaire's
/// edges").
constexpr int kEmitterMaskDilation = 2;

/// Removes the emitter refiner's files from fit folder `dir` (a new stage 1 makes them stale).
void remove_emitter_refiner(const std::string& dir);

/// 1 where `mask` (w × h, 0 or 1) is 1 within `radius` pixels (the square around each pixel), else 0.
std::vector<float> dilate_mask(const std::vector<float>& mask, int w, int h, int radius);

/// Where emitters are seen inside each latent pixel of a w × h view of `scene`:
/// render_emitter_cells at kEmitterMaskCells (geometry, no samples), w × h × kEmitterMaskCells².
std::vector<float> emitter_coverage(const Scene& scene, int w, int h);

/// 1 on the pixels whose emitter coverage differs from `training`'s (the training view's at the
/// same size; empty when the view has another size: then every pixel an emitter is seen in), and
/// on those within `dilation` pixels of one; else 0.
std::vector<float> emitter_mask(const std::vector<float>& coverage, const std::vector<float>& training, int w, int h,
                                int dilation = kEmitterMaskDilation);

/// `refined` with each pixel's `channels` values taken from `emitter_refined` where `mask` is 1.
std::vector<float> take_near_emitters(std::vector<float> refined, const std::vector<float>& emitter_refined,
                                      const std::vector<float>& mask, int channels);

/// Throws std::runtime_error naming `path` unless `emitters` reads what `main` reads besides the
/// latent and AOVs (the transport terms); its emitter cells are rendered for it when they differ.
void check_emitter_refiner_inputs(const RefinerConfig& main, const RefinerConfig& emitters, const std::string& path);

/// The view refined by `main`, and by `emitters` (when given) on emitter_mask of `scene` against
/// `training_coverage` (emitter_coverage of the training view). `in` as `main` reads it.
std::vector<float> refine_with_emitters(const Refiner& main, const Refiner* emitters, const Scene& scene,
                                        const RefinerInput& in, const std::vector<float>& training_coverage);

}  // namespace lpt::pipeline
