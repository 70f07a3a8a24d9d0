#include "pipeline/fit_checkpoint.h"
#include "core/image_io.h"
#include <filesystem>
#include <stdexcept>

namespace lpt::pipeline {

namespace fs = std::filesystem;

nlohmann::json stage1_settings(const FitJob& job) {
    const FitOptions& o = job.options;
    return {{"scene", fs::absolute(job.scene).string()},
            {"defines", job.defines},
            {"target", job.target.empty() ? "" : fs::absolute(job.target).string()},
            {"encode", job.encode},
            {"encode_res", job.encode_res},
            {"ref_spp", job.ref_spp},
            {"ref_tone", job.ref_tone},
            {"synthetic_res", job.synthetic_res},
            {"synthetic_seed", job.synthetic_seed},
            {"param", job.param},
            {"gate", job.gate},
            {"terms", job.terms},
            {"seed", o.seed},
            {"spp", o.spp},
            {"lr", o.lr},
            {"lr_min", o.lr_min},
            {"lr_period", o.lr_period},
            {"lr_t_mult", o.lr_t_mult},
            {"huber_delta", o.huber_delta},
            {"emission_decay", o.emission_decay},
            {"tone", to_string(o.tone)},
            {"patience", o.patience},
            {"min_delta", o.min_delta},
            {"smoothing", o.smoothing},
            {"reuse_paths", o.reuse_paths}};
}

std::string settings_difference(const nlohmann::json& recorded, const nlohmann::json& wanted) {
    for (const auto& [key, value] : wanted.items()) {
        if (!recorded.contains(key)) return "it records no '" + key + "'";
        if (recorded[key] != value)
            return "it was made with " + key + " = " + recorded[key].dump() + ", this fit has " + value.dump();
    }
    return "";
}

bool prepare_checkpoint(const std::string& dir, const nlohmann::json& settings, bool resume, bool restart_if_changed) {
    const fs::path file = fs::path(dir) / "settings.json";
    bool keep = resume;
    if (resume) {
        std::string why = "it records no settings (made before they were recorded)";
        if (!fs::exists(fs::path(dir) / "state.json")) why = "there is none";
        else if (fs::exists(file)) {
            try {
                why = settings_difference(nlohmann::json::parse(read_file(file.string())), settings);
            } catch (const nlohmann::json::exception& e) {
                why = std::string("it is not JSON: ") + e.what();
            }
        }
        if (!why.empty() && !restart_if_changed)
            throw std::runtime_error(file.string() + ": cannot resume this checkpoint: " + why +
                                     "; run without --resume to start again");
        keep = why.empty();
    }
    if (!keep) fs::remove_all(dir);
    fs::create_directories(dir);
    write_text_atomic(file.string(), settings.dump(1));
    return keep;
}

}  // namespace lpt::pipeline
