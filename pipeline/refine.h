// Stage 2 as a library call: trains the per-scene refiner on a fit folder's final render
// (latent.exr, aov.exr) against target.exr (and reference_rgb.exr for LPIPS when present) and
// writes refiner.pt, latent_refined.exr, refiner_loss.csv, metrics.json and decoded_refined.png;
// with RefineJob::emitters the emitter refiner instead (pipeline/emitter_refiner.h).
#pragma once
#include "core/sampler.h"
#include "pipeline/progress.h"
#include "pipeline/refiner_augment.h"
#include "refiner/refiner.h"
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace lpt::pipeline {

struct RefineJob {
    std::string fitdir;
    RefinerConfig net;          ///< expansion, squash, dropout, norm (distance_scale comes from the view)
    RefinerTrainOptions train;  ///< iterations, lr, loss weights, crops, patience, seed, checkpoint_every
    /// Renders of the training view the refiner trains on: the fit's latent.exr and noise_views − 1
    /// more at the fit's final spp with independent samples (seeds no edit frame uses), so that it
    /// learns the scene, not one render's noise (docs/refiner.md "Noise views").
    int noise_views = 1;
    /// Mirrored and rolled copies of the training view, each against its reference moved the same
    /// way and encoded again (needs reference_rgb.exr; docs/refiner.md "Augmentation").
    RefinerAugment augment = RefinerAugment::None;
    /// Train towards each view's reference encoded with the decoder's low-frequency bias
    /// compensated (vae/compensated_encode.h) instead of its plain encoding, target.exr; needs
    /// reference_rgb.exr (docs/refiner.md "Latent target").
    bool compensated_target = false;
    /// With compensated_target: the pixels of the square blocks the bias is averaged over; 0 =
    /// one latent cell (the VAE's downsample factor). Must divide the reference's width and height.
    int latent_target_block = 0;
    /// Apply the trained refiner on windows the size of its training crop (RefinerConfig::tile)
    /// when InstanceNorm is on and the crop is smaller than the view; false: the whole view at once.
    bool windowed_inference = true;
    /// Latent pixels between neighbouring inference windows (RefinerConfig::window_stride): at 4
    /// a 32² window is applied at 8 × 8 offsets per 32² pixels, where half the window's stride
    /// (16) gave 2 × 2; the denser average cut the Cornell box's refined camera-orbit LPIPS by
    /// 6.5 % and MSE×100 by 8.4 % (docs/refiner.md "Window stride"). At most the crop.
    int window_stride = 4;
    std::optional<SamplerKind> sampler;  ///< replaces the fit's for the extra views (--sampler)
    bool resume = false;                 ///< continue from <fitdir>/refiner_checkpoint.pt when it exists
    /// With resume: a checkpoint trained with other settings (refiner_checkpoint.json) is removed
    /// and training starts again, instead of an error (pipeline/fit_checkpoint.h).
    bool restart_if_changed = false;
    std::string lpips_dir;  ///< empty = ../shared/models/lpips
    /// Train the emitter refiner (pipeline/emitter_refiner.h) instead of the main one: its files
    /// are refiner_emitters.pt, refiner_emitters_checkpoint.pt (.json) and
    /// refiner_emitters_loss.csv, and its record is added to metrics.json. It needs refiner.pt
    /// beside it; the training view's refined latent is the main refiner's alone (the emitters
    /// are where training saw them).
    bool emitters = false;
};

struct RefineSummary {
    RefinerTrainResult result;
    nlohmann::json metrics;  ///< what metrics.json holds: rendered / refined / vae_roundtrip
    bool decoded = false;    ///< a VAE was found: decoded_refined.png written, RGB metrics present
};

/// Throws std::invalid_argument naming the option (as the CLI spells it) when a value is out of
/// its range: the command line checks them as it parses, library and Python callers here.
void validate(const RefineJob& job);

/// Removes both refiners' files from fit folder `dir`, with what they wrote (latent_refined.exr,
/// decoded_refined.png, metrics.json): a new stage 1 makes them stale, and an edit would apply
/// them to the new fit's renders.
void remove_refiners(const std::string& dir);

/// Throws Cancelled when the reporter cancels (refiner_checkpoint.pt keeps the last checkpoint).
RefineSummary run_refine(const RefineJob& job, const Reporter& report = {});

}  // namespace lpt::pipeline
