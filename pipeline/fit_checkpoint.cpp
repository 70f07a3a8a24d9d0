#include "pipeline/fit_checkpoint.h"
#include "core/fingerprint.h"
#include "core/image_io.h"
#include "pipeline/fit_folder.h"
#include <filesystem>
#include <stdexcept>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

/// The file's bytes as a fingerprint (a missing file reads as none: its loader names it).
std::string text_fingerprint(const std::string& path) {
    if (!fs::is_regular_file(path)) return "";
    Fingerprint f;
    f.add(read_file(path));
    return "fnv1a64:" + f.hex();
}

}  // namespace

nlohmann::json stage1_settings(const FitJob& job) {
    const FitOptions& o = job.options;
    nlohmann::json settings = fit_model_settings(job);  // the model's own, as fit.json records them
    settings.update({{"target", job.target.empty() ? "" : fs::absolute(job.target).string()},
                     {"encode", job.encode},
                     {"encode_res", job.encode_res},
                     {"ref_spp", job.ref_spp},
                     {"synthetic_res", job.synthetic_res},
                     {"synthetic_seed", job.synthetic_seed},
                     {"spp", o.spp},
                     {"lr", o.lr},
                     {"lr_min", o.lr_min},
                     {"lr_period", o.lr_period},
                     {"lr_t_mult", o.lr_t_mult},
                     {"huber_delta", o.huber_delta},
                     {"emission_decay", o.emission_decay},
                     {"emitter_response_decay", o.emitter_response_decay},
                     // [1], [1, 1] fit as [] does: recorded as [], as checkpoints without a cycle have it
                     {"exposures", exposures_other_than_1(o.exposures).empty() ? std::vector<float>{} : o.exposures},
                     {"patience", o.patience},
                     {"min_delta", o.min_delta},
                     {"smoothing", o.smoothing},
                     {"reuse_paths", o.reuse_paths},
                     // the VAE the target was encoded by, by content (a rerun with another --vae-*)
                     {"vae_encoder", job.encode ? vae_encoder_fingerprint(job.vae) : ""},
                     // the scene's and target's texts, not only their paths: an edited max_depth
                     // in the file resumed where -D integrator.max_depth was refused
                     {"scene_text", text_fingerprint(job.scene)},
                     {"target_file", job.target.empty() ? "" : text_fingerprint(job.target)}});
    return settings;
}

namespace {

/// Settings added after checkpoints began to record theirs, with the value every checkpoint
/// made before them had: one without the key resumes when the setting still has that value.
/// null: the value is not known (the VAE, recorded since session 51; the scene's and target's
/// texts, since session 55), and one without the key
/// resumes whatever the setting is now, as it did before.
const nlohmann::json& settings_added_later() {
    static const nlohmann::json added = {{"emitter_response_decay", 0.0},
                                         {"exposures", nlohmann::json::array()},
                                         {"vae_encoder", nullptr},
                                         {"scene_text", nullptr},
                                         {"target_file", nullptr}};
    return added;
}

}  // namespace

std::string settings_difference(const nlohmann::json& recorded, const nlohmann::json& wanted) {
    const nlohmann::json& added = settings_added_later();
    for (const auto& [key, value] : wanted.items()) {
        const bool has = recorded.contains(key);
        if (!has && !added.contains(key)) return "it records no '" + key + "'";
        if (!has && added[key].is_null()) continue;
        const nlohmann::json& made_with = has ? recorded[key] : added[key];
        if (made_with != value)
            return "it was made with " + key + " = " + made_with.dump() + ", this fit has " + value.dump();
    }
    return "";
}

namespace {

/// Whether the checkpoint recorded in `file` may be resumed with `settings`; "" or why not.
std::string why_not_resumable(const fs::path& file, const nlohmann::json& settings) {
    if (!fs::exists(file)) return "it records no settings (made before they were recorded)";
    try {
        return settings_difference(nlohmann::json::parse(read_file(file.string())), settings);
    } catch (const nlohmann::json::exception& e) {
        return std::string("it is not JSON: ") + e.what();
    }
}

/// The shared rule: resume only a checkpoint of the same settings; another one is an error, or
/// removed with restart_if_changed. Returns whether to resume.
bool keep_checkpoint(const fs::path& settings_file, const nlohmann::json& settings, bool resume, bool restart,
                     const std::string& none_why) {
    if (!resume) return false;
    const std::string why = none_why.empty() ? why_not_resumable(settings_file, settings) : none_why;
    if (!why.empty() && !restart)
        throw std::runtime_error(settings_file.string() + ": cannot resume this checkpoint: " + why +
                                 "; run without --resume to start again");
    return why.empty();
}

}  // namespace

bool prepare_checkpoint(const std::string& dir, const nlohmann::json& settings, bool resume, bool restart_if_changed) {
    const fs::path file = fs::path(dir) / "settings.json";
    const bool none = !fs::exists(fs::path(dir) / "state.json");
    const bool keep = keep_checkpoint(file, settings, resume, restart_if_changed, none ? "there is none" : "");
    if (!keep) fs::remove_all(dir);
    fs::create_directories(dir);
    write_text_atomic(file.string(), settings.dump(1));
    return keep;
}

nlohmann::json stage2_settings(const RefineJob& job) {
    const RefinerTrainOptions& t = job.train;
    // At a constant rate the iteration count only says where to stop, so a finished training
    // may be extended with --resume; along the cosine it shapes every step's rate.
    nlohmann::json s = {{"fitdir", fs::absolute(job.fitdir).string()},
                        {"expansion", job.net.expansion},
                        {"squash", job.net.squash},
                        {"dropout", job.net.dropout},
                        {"norm", job.net.instance_norm ? "instance" : "none"},
                        {"lr", t.lr},
                        {"lr_decay", t.cosine_decay ? "cosine" : "none"},
                        {"w_mse", t.w_mse},
                        {"w_ssim", t.w_ssim},
                        {"w_lpips", t.w_lpips},
                        {"crop", t.crop},
                        {"lpips_crop", t.lpips_crop},
                        {"patience", t.patience},
                        {"min_delta", t.min_delta},
                        {"seed", t.seed},
                        {"noise_views", job.noise_views},
                        {"augment", to_string(job.augment)}};
    if (t.cosine_decay) s["iterations"] = t.iterations;
    if (job.net.arch != RefinerArch::Conv) s["arch"] = to_string(job.net.arch);  // older checkpoints resume
    if (job.net.terms) s["inputs"] = "terms";
    if (job.net.emitter_cells) s["emitter_cells"] = job.net.emitter_cells;
    if (job.compensated_target) s["latent_target"] = "compensated";
    if (job.latent_target_block) s["latent_target_block"] = job.latent_target_block;
    if (t.input_noise > 0.f) s["input_noise"] = t.input_noise;
    return s;
}

bool prepare_refiner_checkpoint(const std::string& checkpoint_path, const nlohmann::json& settings, bool resume,
                                bool restart_if_changed) {
    const fs::path file = fs::path(checkpoint_path).replace_extension(".json");
    const bool keep = keep_checkpoint(file, settings, resume, restart_if_changed, "");
    if (!keep) fs::remove(checkpoint_path);
    write_text_atomic(file.string(), settings.dump(1));
    return keep;
}

}  // namespace lpt::pipeline
