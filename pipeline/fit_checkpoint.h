// Which stage-1 checkpoint a `fit --resume` may continue: the checkpoint folder records the
// settings that shape the result (scene, target, model, optimiser), and a resumed fit checks them,
// so a fit rerun with a changed setting never silently continues the old one's parameters.
#pragma once
#include "pipeline/fit.h"
#include <nlohmann/json.hpp>
#include <string>

namespace lpt::pipeline {

/// What determines stage 1's result besides its length: every FitJob field that the target, the
/// model or the optimiser reads (not iterations, final_spp, threads or checkpoint_every).
nlohmann::json stage1_settings(const FitJob& job);

/// "" when `recorded` (a checkpoint's settings.json) equals `wanted`; otherwise one sentence
/// naming the first setting that differs, with both values.
std::string settings_difference(const nlohmann::json& recorded, const nlohmann::json& wanted);

/// Prepares <checkpoint_dir> for a fit with `settings` and returns whether to resume from it:
/// without `resume` the old checkpoint is removed; with it, a checkpoint whose settings differ
/// (or that has none recorded) is an error naming checkpoint_dir/settings.json and the setting,
/// or with `restart_if_changed` is removed and the fit starts again (the workflow's choice).
/// The settings are written before any new checkpoint, atomically.
bool prepare_checkpoint(const std::string& checkpoint_dir, const nlohmann::json& settings, bool resume,
                        bool restart_if_changed);

}  // namespace lpt::pipeline
