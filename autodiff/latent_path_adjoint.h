// Path replay backpropagation for the latent image Ĩ = Ĩe + Ĩa + Ĩc (before the tone curve).
// Given d_image = ∂loss/∂Ĩ (16 floats per pixel, the primal's resolution), re-traces the
// primal's paths with the same random numbers and adds ∂loss/∂value into the model's ParamStore
// grad_values(): L̃e, L̃a, L̃c, background and every BSDF coefficient. Sampling decisions, MIS
// weights, pdfs and Russian roulette are constants (as in Vicini et al. 2021); nothing is divided
// by a BSDF value. Deterministic: per-tile gradient buffers are reduced in tile order.
// Equations: docs/path-replay.md.
#pragma once
#include "latent/latent_model.h"
#include "integrators/path.h"
#include <vector>

namespace lpt {

/// `options` must be those of the primal render (seed, spp, resolution, depth, strategy).
/// Returns the primal image of the replay (identical to the primal's), handy for checks.
std::vector<float> backward_latent(LatentModel& model, const RenderOptions& options, const std::vector<float>& d_image,
                                   RenderStats* stats = nullptr);

}  // namespace lpt
