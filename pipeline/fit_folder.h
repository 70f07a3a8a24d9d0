// A fit folder: what `latentpt fit` writes and everything after it reads. fit.json (the
// manifest: scene, -D values, model choices, latent size, VAE) is written and read here only;
// load_fit_folder rebuilds the fitted latent model from it and params.json.
#pragma once
#include "autodiff/tone_curve.h"
#include "core/image_io.h"
#include "core/sampler.h"
#include "core/scene.h"
#include "latent/latent_model.h"
#include "pipeline/vae_source.h"
#include <map>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lpt {
struct FitState;
}

namespace lpt::pipeline {

struct FitJob;

struct FitFolder {
    std::string dir;
    nlohmann::json manifest;       ///< fit.json
    std::unique_ptr<Scene> scene;  ///< owned here: the model refers to it
    /// The -D values `scene` was loaded with: fit.json's, with the loader's overrides on top.
    std::map<std::string, std::string> defines;
    std::unique_ptr<LatentModel> model;
    ToneCurve tone = ToneCurve::Clip;
    int latent_width = 0, latent_height = 0;
    std::string ref_tone = "clip";
    VaeSource vae;  ///< the VAE the fit used
};

/// Throws std::runtime_error naming the file for a missing or malformed fit.json / params.json.
/// `defines` override the fit's own -D values, `sampler` the one the fit was made with (fit.json's
/// "sampler" when the fit was given one, else the scene file's).
FitFolder load_fit_folder(const std::string& dir, const std::map<std::string, std::string>& defines = {},
                          std::optional<SamplerKind> sampler = std::nullopt);

/// The scene as fitted, with fit.json's own -D values only: what the training view showed, which
/// a FitFolder loaded with other defines (a camera's field of view) may no longer be.
Scene load_fitted_scene(const FitFolder& fit);

/// The fitted model's tone-mapped latent of its (possibly edited) scene at w × h, spp and seed:
/// what edited frames and the refiner's extra training renders are made of.
std::vector<float> render_fit_latent(const FitFolder& fit, int w, int h, int spp, uint64_t seed);

/// The same render with its transport terms: `toned` is render_fit_latent's latent, `terms` the
/// Ĩe, Ĩa, Ĩc it sums, interleaved per pixel (RefinerInput::terms), linear.
struct FitRender {
    std::vector<float> toned, terms;
};
FitRender render_fit_terms(const FitFolder& fit, int w, int h, int spp, uint64_t seed);

/// Ĩe, Ĩa, Ĩc images (`channels` per pixel each) interleaved per pixel as RefinerInput::terms.
std::vector<float> interleave_terms(const std::vector<float>& e, const std::vector<float>& a,
                                    const std::vector<float>& c, int channels);

/// Throws std::invalid_argument unless `gate` is "shadowed" or "visible" and `terms` letters of
/// "eac"; `prefix` goes before the names in the message ("--" where they are flags).
void check_terms(const std::string& gate, const std::string& terms, const std::string& prefix = "");

/// Sets the model's Ĩc gate ("shadowed" | "visible") and rendered terms (letters of "eac");
/// check_terms refuses others (unchecked, "xyz" rendered zeros and "visble" meant shadowed).
void configure_terms(LatentModel& model, const std::string& gate, const std::string& terms);

/// What makes a fit's model what it is (scene, defines, parameterisation, gate, terms, tone,
/// seed, reference tone, sampler): the keys fit.json and the stage-1 checkpoint's settings
/// share. A key added here makes older checkpoints refuse to resume (fit_checkpoint.cpp's
/// settings_added_later lists the exceptions).
nlohmann::json fit_model_settings(const FitJob& job);

/// fit.json of a finished stage 1: fit_model_settings, the latent size and VAE (everything
/// load_fit_folder needs), plus how the stage went.
nlohmann::json fit_manifest(const FitJob& job, int latent_width, int latent_height, double final_loss,
                            const lpt::FitState& state);

/// The VAE recorded in a parsed fit.json (defaults resolved); manifest_vae reads the file.
VaeSource vae_source_of(const nlohmann::json& manifest);
VaeSource manifest_vae(const std::string& fit_json_path);

/// An image of a fit folder with `channels` channels (and w x h when w > 0); throws naming the
/// file when it is missing or differs.
Image read_fit_image(const std::string& path, int channels, int w, int h);
/// A 16-channel latent map as a float EXR (channels C00..C15).
void write_latent(const std::string& path, int w, int h, const std::vector<float>& data);

}  // namespace lpt::pipeline
