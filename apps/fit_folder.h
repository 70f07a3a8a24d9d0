// A fit folder (written by `latentpt fit`) loaded back: the scene with its -D overrides, the
// latent model with the fitted parameters, terms, gate and tone curve, and the latent size.
// Shared by `render <fitdir> --edit` and `bench --equal-error`.
#pragma once
#include "apps/commands.h"
#include "autodiff/fit.h"
#include "latent/latent_model.h"
#include "autodiff/tone_curve.h"
#include "core/scene.h"
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

namespace lpt::app {

struct FitFolder {
    std::string dir;
    nlohmann::json manifest;                 ///< fit.json
    std::unique_ptr<Scene> scene;            ///< owned here: the model refers to it
    std::unique_ptr<LatentModel> model;
    ToneCurve tone = ToneCurve::Clip;
    int latent_width = 0, latent_height = 0;
    std::string ref_tone = "clip";
    VaeSource vae;                           ///< the VAE the fit used
};

/// The VAE recorded in a parsed fit.json (defaults resolved); manifest_vae reads the file.
VaeSource vae_source_of(const nlohmann::json& manifest);

/// Throws std::runtime_error naming the file for a missing or malformed fit.json / params.json.
/// `defines` override the fit's own -D values.
FitFolder load_fit_folder(const std::string& dir, const std::map<std::string, std::string>& defines = {});

}  // namespace lpt::app
