// Stage 1 of `latentpt fit`: per-shape latent parameters fitted to a target latent map by Adam
// on the Huber loss of the tone-mapped render, with path-replay gradients, cosine annealing with
// warm restarts, early stopping that restores the best parameters, and checkpoints that resume to
// the same result as an uninterrupted run. docs/fitting.md.
#pragma once
#include "autodiff/adam.h"
#include "latent/latent_model.h"
#include "autodiff/tone_curve.h"
#include <functional>
#include <string>
#include <vector>

namespace lpt {

struct FitOptions {
    int iterations = 3000;
    int spp = 16;  ///< per iteration, fresh random numbers each iteration
    uint64_t seed = 0;
    float lr = 1e-3f, lr_min = 0.f;
    int lr_period = 500, lr_t_mult = 1;
    float huber_delta = 1.f;
    /// λ of the penalty λ·Σ L̃e² on every emitter's latent radiance (docs/fitting.md (17)); 0 = off.
    /// With the flat term, a light's L̃e + L̃a is all its own pixels see, so the loss alone leaves
    /// L̃e free to grow along that valley (and its indirect noise with it).
    float emission_decay = 0.f;
    /// μ of the penalty μ·Σ (L̃a² + L̃c²) on the flat and occlusion responses of every emitting
    /// shape (docs/fitting.md (18)); 0 = off. Closes the same valley from the other side: on a
    /// light's own pixels both act as flat terms beside L̃e; pinned near 0, those pixels fix L̃e
    /// without pulling down an L̃e that the room's light needs.
    float emitter_response_decay = 0.f;
    /// Light exposures the iterations cycle through: iteration i renders with every light's L̃e
    /// times k = exposures[i % size] and matches the target of that k (docs/fitting.md "Exposure
    /// cycle"). Empty = {1}: the training view alone. A view shows the sum of the terms; how much
    /// of it is light (Ĩe) and how much flat response (Ĩa, Ĩc) only a change of the light shows.
    /// The logged and smoothed losses (early stopping's too) are each iteration's own exposure's.
    std::vector<float> exposures;
    ToneCurve tone = ToneCurve::Clip;
    int patience = 300;  ///< early stopping on the smoothed loss; 0 = off
    float min_delta = 1e-5f;
    float smoothing = 0.95f;  ///< exponential moving average of the noisy per-iteration loss
    /// 0: fresh paths every iteration, re-traced by the adjoint (path replay, memory of one
    /// wavefront). K >= 1: trace and store one frame's paths every K iterations and replay the
    /// stored paths (forward and adjoint) in between: no rays traced, memory ~56 B per event
    /// (docs/path-replay.md (6), measured in docs/performance.md).
    /// The default, 8, is what `latentpt fit` uses (one source: the CLI shows this value).
    int reuse_paths = 8;
    int checkpoint_every = 100;  ///< 0 = never; rounded up to a multiple of reuse_paths
    std::string checkpoint_dir;  ///< empty = no checkpoints
};

/// The latent a fit matches while every light is `exposure` times as bright: exposure 1 is the
/// training view's target.
struct ExposureTarget {
    float exposure = 1.f;
    std::vector<float> latent;
};

struct FitRecord {
    int iteration;
    double loss, smoothed;
    float lr;
    double seconds;
    bool refused = false;           ///< the gradient had NaN/Inf entries: the step was skipped
    std::string refused_parameter;  ///< when refused: the first slice with a bad gradient
};

struct FitState {
    int next_iteration = 0;
    AdamState adam;
    double smoothed = -1.0;  ///< < 0 before the first iteration
    /// The iteration whose parameters the fit returns and its smoothed loss: the best one with
    /// early stopping, the last one without (patience 0); −1 before the first iteration.
    double best_loss = 1e300;
    int best_iteration = -1, bad_updates = 0;
    std::vector<float> best_raw;  ///< the parameters at best_iteration
    int skipped_steps = 0;        ///< iterations whose gradient had NaN/Inf (step refused)
    std::vector<FitRecord> history;
};

/// Emission decay: the penalty λ·Σ L̃e² over every "Le" slice (docs/fitting.md (17)): adds its
/// derivative 2λ·L̃e to the value gradients (before ParamStore::backward) and returns its value.
double add_emission_decay(ParamStore& params, float lambda);

/// Emitter response decay: the penalty μ·Σ (L̃a² + L̃c²) over the "La" and "Lc" slices of every
/// shape that has an "Le" slice (docs/fitting.md (18)); gradients and return value as
/// add_emission_decay.
double add_emitter_response_decay(ParamStore& params, float mu);

/// Ĩe + Ĩa + Ĩc of `films` with the tone curve applied: the one place the terms become the latent
/// the loss, the refiner and the decoder see.
std::vector<float> toned_sum(const TermFilms<kLatentChannels>& films, ToneCurve tone);

/// Latent render with the fit's tone curve applied: what the loss compares with the target.
std::vector<float> render_toned(const LatentModel& model, const RenderOptions& options, ToneCurve tone);

/// Runs (or continues, from `state`) the fit; ends with the best parameters in `model`.
/// `on_iteration` is called after every iteration (progress, logging); returning false stops.
FitState fit_latent(LatentModel& model, const std::vector<float>& target, int width, int height,
                    const FitOptions& options, FitState state = {},
                    const std::function<bool(const FitRecord&, const FitState&)>& on_iteration = {});
/// The same with one target per light exposure: every value of options.exposures (1 if empty)
/// needs one; std::invalid_argument otherwise.
FitState fit_latent(LatentModel& model, const std::vector<ExposureTarget>& targets, int width, int height,
                    const FitOptions& options, FitState state = {},
                    const std::function<bool(const FitRecord&, const FitState&)>& on_iteration = {});
/// The light exposure iteration `iteration` fits: options.exposures cycled, 1 if empty.
float exposure_at(const FitOptions& options, int iteration);
/// The distinct values of `exposures` other than 1, in their first order: the exposures that need
/// a target of their own (none: the fit is the training view's alone).
std::vector<float> exposures_other_than_1(const std::vector<float>& exposures);
/// Turns the gradients of a render with every light's L̃e times k into those of L̃e itself:
/// d/dL̃e = k · d/d(k·L̃e) on every "Le" slice.
void scale_emission_gradients(ParamStore& params, float k);

/// Checkpoint = params (raw) + Adam state + early-stopping state + history, written atomically
/// into `dir`; load throws std::runtime_error naming the file on any mismatch.
void save_checkpoint(const std::string& dir, const LatentModel& model, const FitState& state);
FitState load_checkpoint(const std::string& dir, LatentModel& model);

}  // namespace lpt
