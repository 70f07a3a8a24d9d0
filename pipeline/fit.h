// Stage 1 of the paper's pipeline as a library call: the target (a latent EXR, the VAE encoding of
// an RGB path trace, or a synthetic one), the fit, and the fit folder it leaves: params.json,
// fit.json, the final latent and its three terms, aov.exr, loss.csv, pictures, checkpoints. With
// job.refiner, stage 2 follows (pipeline/refine.h). The CLI's `latentpt fit` only fills a FitJob.
#pragma once
#include "autodiff/fit.h"
#include "pipeline/progress.h"
#include "pipeline/refine.h"
#include "pipeline/vae_source.h"
#include <map>
#include <optional>
#include <string>

namespace lpt::pipeline {

struct FitJob {
    std::string scene;                           ///< .json or Mitsuba 3 .xml
    std::map<std::string, std::string> defines;  ///< -D overrides
    std::optional<SamplerKind> sampler;          ///< replaces the scene file's (--sampler); kept in fit.json
    std::string out = "fit-out";                 ///< the fit folder

    // The target: `target` if given, else the encoded RGB reference with `encode`, else synthetic.
    std::string target;                  ///< 16-channel float EXR at latent resolution
    bool encode = false;                 ///< target = VAE encoding of the scene path traced in RGB
    std::string encode_res = "256x256";  ///< image resolution for `encode` (latent = image / 8)
    int ref_spp = 256;
    std::string ref_tone = "clip";        ///< clip to [0, 1] or reinhard |x|/(1+|x|), then gamma 1/2.2
    std::string reference_cache;          ///< with `encode`: folder sharing the traced reference between fits
    std::string synthetic_res = "32x32";  ///< latent resolution of the synthetic target
    uint64_t synthetic_seed = 1;

    // The model and its optimisation. options.seed seeds the parameters, every iteration's paths,
    // the final render (seed + 1) and the refiner; options.checkpoint_dir is <out>/checkpoint.
    std::string param = "code";     ///< parameterisation: code, paper, classic, gain
    std::string gate = "shadowed";  ///< Ĩc gate: shadowed (1 − V) or visible (V)
    std::string terms = "eac";      ///< latent terms rendered: any of e, a, c
    FitOptions options;
    int final_spp = 256;  ///< samples per pixel of the final render
    bool resume = false;  ///< continue from <out>/checkpoint (and the refiner's)
    /// With resume: a checkpoint made with other stage-1 settings is removed and the fit starts
    /// again, instead of an error (pipeline/fit_checkpoint.h). What a workflow wants.
    bool restart_if_changed = false;
    VaeSource vae;

    bool refiner = true;  ///< run stage 2 afterwards
    RefineJob refine;     ///< stage-2 settings (fitdir, seed and resume are filled in)
};

/// Checks the job's names and letters (param, gate, terms, tones); throws std::invalid_argument.
void validate(const FitJob& job);

struct FitSummary {
    int latent_width = 0, latent_height = 0;
    double final_loss = 0;                 ///< Huber loss of the final render against the target
    FitState state;                        ///< history, best iteration, refused steps
    std::optional<RefineSummary> refined;  ///< stage 2, when the job ran it
};

/// Runs stage 1 (and stage 2 when job.refiner) into job.out. Throws Cancelled when the reporter
/// cancels (the last periodic checkpoint stays, so job.resume continues from it).
FitSummary run_fit(const FitJob& job, const Reporter& report = {});

}  // namespace lpt::pipeline
