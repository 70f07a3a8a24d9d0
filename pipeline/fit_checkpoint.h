// Which checkpoint a `--resume` may continue: a stage-1 checkpoint folder and a refiner
// checkpoint record the settings that shape their result (scene, target, model, optimiser,
// network), and a resumed run checks them, so a run with a changed setting never silently
// continues the old one's state.
#pragma once
#include "pipeline/fit.h"
#include "pipeline/refine.h"
#include <nlohmann/json.hpp>
#include <string>

namespace lpt::pipeline {

/// What determines stage 1's result besides its length: every FitJob field that the target, the
/// model or the optimiser reads (not iterations, final_spp, threads or checkpoint_every).
nlohmann::json stage1_settings(const FitJob& job);

/// "" when `recorded` (a checkpoint's settings.json) equals `wanted`; otherwise one sentence
/// naming the first setting that differs, with both values. A setting added after checkpoints
/// began recording theirs (emitter_response_decay) that `recorded` lacks counts as its old value.
std::string settings_difference(const nlohmann::json& recorded, const nlohmann::json& wanted);

/// Prepares <checkpoint_dir> for a fit with `settings` and returns whether to resume from it:
/// without `resume` the old checkpoint is removed; with it, a checkpoint whose settings differ
/// (or that has none recorded) is an error naming checkpoint_dir/settings.json and the setting,
/// or with `restart_if_changed` is removed and the fit starts again (the workflow's choice).
/// The settings are written before any new checkpoint, atomically.
bool prepare_checkpoint(const std::string& checkpoint_dir, const nlohmann::json& settings, bool resume,
                        bool restart_if_changed);

/// What determines stage 2's weights: the network, the training options and the training views
/// (not checkpoint_every, the inference window or where LPIPS weights live; the iteration count
/// only with the cosine decay, which it shapes).
nlohmann::json stage2_settings(const RefineJob& job);

/// As prepare_checkpoint for the refiner's one-file checkpoint, whose settings live beside it in
/// <checkpoint>.json (refiner_checkpoint.json). `resume` is true only when the checkpoint exists;
/// without resuming, the old checkpoint is removed.
bool prepare_refiner_checkpoint(const std::string& checkpoint_path, const nlohmann::json& settings, bool resume,
                                bool restart_if_changed);

}  // namespace lpt::pipeline
