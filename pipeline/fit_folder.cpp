#include "pipeline/fit_folder.h"
#include "autodiff/fit.h"
#include "core/film.h"
#include "core/json_number.h"
#include "core/scene_loader.h"
#include "integrators/path.h"
#include "pipeline/fit.h"
#include "pipeline/paths.h"
#include <filesystem>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

nlohmann::json parse_json_file(const std::string& path) {
    try {
        return nlohmann::json::parse(read_file(path));
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(path + ": malformed: " + e.what());
    }
}

}  // namespace

std::vector<float> render_fit_latent(const FitFolder& fit, int w, int h, int spp, uint64_t seed) {
    return render_toned(*fit.model, RenderOptions::from_scene(*fit.scene, w, h, spp, seed), fit.tone);
}

FitRender render_fit_terms(const FitFolder& fit, int w, int h, int spp, uint64_t seed) {
    const LatentModel& model = *fit.model;
    const TermFilms<kLatentChannels> films = render_latent_terms<kLatentChannels>(
        model.scene(), model.spectra(), model.terms(), RenderOptions::from_scene(*fit.scene, w, h, spp, seed));
    FitRender r;
    r.toned = toned_sum(films, fit.tone);
    r.terms = interleave_terms(films.e.develop(), films.a.develop(), films.c.develop(), kLatentChannels);
    return r;
}

std::vector<float> interleave_terms(const std::vector<float>& e, const std::vector<float>& a,
                                    const std::vector<float>& c, int channels) {
    std::vector<float> out;
    out.reserve(e.size() * 3);
    for (size_t p = 0; p < e.size(); p += size_t(channels))
        for (const std::vector<float>* term : {&e, &a, &c})
            out.insert(out.end(), term->begin() + std::ptrdiff_t(p), term->begin() + std::ptrdiff_t(p) + channels);
    return out;
}

void check_terms(const std::string& gate, const std::string& terms, const std::string& prefix) {
    if (terms.empty() || terms.find_first_not_of("eac") != std::string::npos)
        throw std::invalid_argument(prefix + "terms take letters from e, a, c; got '" + terms + "'");
    if (gate != "shadowed" && gate != "visible")
        throw std::invalid_argument(prefix + "gate is shadowed or visible, got '" + gate + "'");
}

void configure_terms(LatentModel& model, const std::string& gate, const std::string& terms) {
    check_terms(gate, terms);
    LatentTerms<kLatentChannels>& t = model.terms();
    t.gate = gate == "visible" ? OcclusionGate::Visible : OcclusionGate::Shadowed;
    t.emission = terms.find('e') != std::string::npos;
    t.ambient = terms.find('a') != std::string::npos;
    t.occlusion = terms.find('c') != std::string::npos;
}

FitFolder load_fit_folder(const std::string& dir_name, const std::map<std::string, std::string>& overrides,
                          std::optional<SamplerKind> sampler) {
    const fs::path dir(dir_name);
    if (!fs::is_directory(dir))
        throw std::runtime_error(dir_name + ": not a folder (expected a fit folder made by latentpt fit)");
    const std::string manifest_path = (dir / "fit.json").string();
    if (!fs::exists(manifest_path)) throw std::runtime_error(manifest_path + ": missing: not a latentpt fit folder");
    FitFolder f;
    f.dir = dir_name;
    f.manifest = parse_json_file(manifest_path);
    const nlohmann::json& m = f.manifest;
    if (!m.is_object()) throw std::runtime_error(manifest_path + ": expected a JSON object");
    try {
        std::map<std::string, std::string>& defines = f.defines;
        defines = m.value("defines", std::map<std::string, std::string>{});
        for (const auto& [k, v] : overrides) defines[k] = v;
        const std::string scene = m.at("scene").get<std::string>();
        std::error_code ec;  // a name too long for the file system is an error, not an exception
        if (!fs::exists(scene, ec))
            throw std::runtime_error(manifest_path + ": field 'scene': " + scene +
                                     " does not exist (moved since the fit? fit.json names it by path)");
        if (!sampler && m.contains("sampler"))
            sampler = sampler_choice(m.at("sampler").get<std::string>(), manifest_path + ": field 'sampler'");
        f.scene = std::make_unique<Scene>(load_scene(scene, defines, sampler));
        f.model = std::make_unique<LatentModel>(*f.scene, parameterisation_from_string(m.value("param", "code")), 0);
        const std::string params_path = (dir / "params.json").string();
        if (!fs::exists(params_path)) throw std::runtime_error(params_path + ": missing");
        f.model->params().load_json(read_file(params_path), params_path);
        configure_terms(*f.model, m.value("gate", "shadowed"), m.value("terms", "eac"));
        f.model->sync();
        f.tone = parse_tone_curve(m.value("tone", "clip"));
        f.latent_width = json_int(m.at("latent_width"), manifest_path, "latent_width", 1, 1 << 20);
        f.latent_height = json_int(m.at("latent_height"), manifest_path, "latent_height", 1, 1 << 20);
        // before anything is traced at that size (the unseen-emitter grid alone ran for minutes
        // without a word at 100000²): a latent film, its AOVs and the decoded picture
        try {
            check_image_fits(f.latent_width, f.latent_height, 2 * kLatentChannels + 1);
            check_image_fits(8 * f.latent_width, 8 * f.latent_height, 3);
        } catch (const std::length_error& e) {
            throw std::runtime_error(manifest_path + ": latent_width x latent_height: " + e.what());
        }
        f.ref_tone = m.value("ref_tone", "clip");
        f.vae = vae_source_of(m);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(manifest_path + ": " + e.what());
    } catch (const std::invalid_argument& e) {  // an unknown "param" or "tone" name
        throw std::runtime_error(manifest_path + ": " + e.what());
    }
    return f;
}

nlohmann::json fit_model_settings(const FitJob& job) {
    nlohmann::json m = {{"scene", fs::absolute(job.scene).string()},
                        {"defines", job.defines},
                        {"param", job.param},
                        {"gate", job.gate},
                        {"terms", job.terms},
                        {"tone", to_string(job.options.tone)},
                        {"seed", job.options.seed},
                        {"ref_tone", job.ref_tone}};
    if (job.sampler) m["sampler"] = sampler_name(*job.sampler);  // absent: the scene file's
    return m;
}

nlohmann::json fit_manifest(const FitJob& job, int w, int h, double final_loss, const FitState& state) {
    const FitOptions& o = job.options;
    nlohmann::json m = fit_model_settings(job);
    m["latent_width"] = w;
    m["latent_height"] = h;
    m["vae_dir"] = default_vae_dir(job.vae.dir);
    if (job.vae.torchscript())
        m["vae_torchscript"] = {{"encoder", fs::absolute(job.vae.encoder).string()},
                                {"decoder", fs::absolute(job.vae.decoder).string()},
                                {"config", fs::absolute(job.vae.config).string()}};
    // How stage 1 went, for comparing runs (e.g. --reuse-paths) without parsing logs.
    m["stage1"] = {{"final_loss", final_loss},
                   {"final_spp", job.final_spp},
                   {"iterations_run", state.next_iteration},
                   {"best_iteration", state.best_iteration},
                   {"seconds", state.history.empty() ? 0.0 : state.history.back().seconds},
                   {"spp", o.spp},
                   {"reuse_paths", o.reuse_paths},
                   {"emission_decay", o.emission_decay},
                   {"emitter_response_decay", o.emitter_response_decay},
                   {"exposures", o.exposures},
                   {"skipped_steps", state.skipped_steps}};
    return m;
}

VaeSource vae_source_of(const nlohmann::json& m) {
    VaeSource s;
    s.dir = m.value("vae_dir", default_vae_dir(""));
    if (m.contains("vae_torchscript")) {
        const auto& t = m["vae_torchscript"];
        s.encoder = t.value("encoder", "");
        s.decoder = t.value("decoder", "");
        s.config = t.value("config", "");
    }
    return s;
}

VaeSource manifest_vae(const std::string& path) { return vae_source_of(parse_json_file(path)); }

Scene load_fitted_scene(const FitFolder& fit) {
    const std::string manifest_path = (fs::path(fit.dir) / "fit.json").string();
    try {
        return load_scene(fit.manifest.at("scene").get<std::string>(),
                          fit.manifest.value("defines", std::map<std::string, std::string>{}));
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(manifest_path + ": " + e.what());
    }
}

Image read_fit_image(const std::string& path, int channels, int w, int h) {
    if (!fs::exists(path)) throw std::runtime_error(path + ": missing (run latentpt fit first)");
    Image img = read_image(path);
    if (img.channels != channels || (w > 0 && (img.width != w || img.height != h)))
        throw std::runtime_error(path + ": expected " +
                                 (w > 0 ? std::to_string(w) + "x" + std::to_string(h) + " with " : std::string()) +
                                 std::to_string(channels) + " channels, found " + std::to_string(img.width) + "x" +
                                 std::to_string(img.height) + " with " + std::to_string(img.channels));
    require_finite_pixels(img, path);  // a NaN target let the refiner refuse every step, exit 0
    return img;
}

void write_latent(const std::string& path, int w, int h, const std::vector<float>& data) {
    write_exr(path, Image{w, h, kLatentChannels, data, {}});
}

}  // namespace lpt::pipeline
