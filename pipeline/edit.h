// Edited views of a fitted latent scene as a library call: camera / shape edits frame by frame,
// each frame's latent (tone-mapped, what the VAE reads), refined latent and AOVs when the fit has
// a refiner, decoded PNGs when its VAE is here, and with `reference` the RGB path trace of the
// same edit encoded by the VAE and per-frame errors in metrics.csv (docs/metrics.md).
#pragma once
#include "core/sampler.h"
#include "pipeline/progress.h"
#include "pipeline/reference.h"
#include <cstdint>
#include <map>
#include <optional>
#include <string>

namespace lpt::pipeline {

struct EditJob {
    std::string fitdir, edits;                   ///< fit folder, edits.json
    std::string out = "edit-out";                ///< output folder
    std::map<std::string, std::string> defines;  ///< override the fit's -D values
    std::optional<SamplerKind> sampler;          ///< replaces the fit's (--sampler)
    int width = 0, height = 0;                   ///< latent resolution; 0 = the fit's
    int spp = 64;
    uint64_t seed = 0;  ///< frame i uses seed + i
    bool reference = false;
    int ref_spp = 256;
    /// The references' seed: another one traces independent references of the same frames, to
    /// measure their noise (docs/metrics.md "Reference noise").
    uint64_t ref_seed = kReferenceSeed;
    std::string reference_cache;  ///< keeps path-traced reference frames for reuse
    /// Keeps the frames that show the training view (frame 0 of every sequence), rendered,
    /// decoded and scored, for the other sequences of the same fit and settings
    /// (pipeline/frame_cache.h); empty: every job renders its own.
    std::string frame_cache;
    /// Only frames first_frame..last_frame (inclusive; -1 = the last): a sequence split into jobs
    /// gives the same frame files as one job, since frame i depends on i alone (seed + i). A
    /// job given a range (last_frame >= 0) writes its metrics rows to metrics_<first>-<last>.csv,
    /// so jobs never share a file.
    int first_frame = 0, last_frame = -1;
    int frame_step = 1;  ///< only every frame_step-th frame from first_frame (a stated subset)
    /// Skip frames an earlier (killed) run finished. Every frame ends by writing frame_NNNN.done
    /// (a key of the fit and settings, then its metrics row), atomically and last, so one there
    /// means the frame is whole; one with another key (another fit, refiner or settings) is
    /// rendered again.
    bool resume = false;
};

/// Returns the number of frames in the range (rendered now or, with resume, before). Throws Cancelled when the reporter
/// cancels, and std::invalid_argument for a frame range outside the sequence.
int render_edits(const EditJob& job, const Reporter& report = {});

}  // namespace lpt::pipeline
