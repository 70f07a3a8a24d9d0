#include "apps/fit_folder.h"
#include "core/image_io.h"
#include "core/scene_loader.h"
#include <filesystem>

namespace lpt::app {

namespace fs = std::filesystem;

FitFolder load_fit_folder(const std::string& dir_name, const std::map<std::string, std::string>& overrides) {
    const fs::path dir(dir_name);
    if (!fs::is_directory(dir)) throw std::runtime_error(dir_name + ": not a folder (expected a fit folder made by latentpt fit)");
    const std::string manifest_path = (dir / "fit.json").string();
    if (!fs::exists(manifest_path)) throw std::runtime_error(manifest_path + ": missing: not a latentpt fit folder");
    FitFolder f;
    f.dir = dir_name;
    try {
        f.manifest = nlohmann::json::parse(read_file(manifest_path));
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(manifest_path + ": malformed: " + e.what());
    }
    const nlohmann::json& m = f.manifest;
    try {
        std::map<std::string, std::string> defines = m.value("defines", std::map<std::string, std::string>{});
        for (const auto& [k, v] : overrides) defines[k] = v;
        f.scene = std::make_unique<Scene>(load_scene(m.at("scene").get<std::string>(), defines));
        f.model = std::make_unique<LatentModel>(*f.scene, parameterisation_from_string(m.value("param", "code")), 0);
        const std::string params_path = (dir / "params.json").string();
        if (!fs::exists(params_path)) throw std::runtime_error(params_path + ": missing");
        f.model->params().load_json(read_file(params_path), params_path);
        LatentTerms<kLatentChannels>& t = f.model->terms();
        t.gate = m.value("gate", "shadowed") == "visible" ? OcclusionGate::Visible : OcclusionGate::Shadowed;
        const std::string terms = m.value("terms", "eac");
        t.emission = terms.find('e') != std::string::npos;
        t.ambient = terms.find('a') != std::string::npos;
        t.occlusion = terms.find('c') != std::string::npos;
        f.model->sync();
        f.tone = parse_tone_curve(m.value("tone", "clip"));
        f.latent_width = m.at("latent_width");
        f.latent_height = m.at("latent_height");
        f.ref_tone = m.value("ref_tone", "clip");
        f.vae = vae_source_of(m);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(manifest_path + ": " + e.what());
    }
    return f;
}

}  // namespace lpt::app
