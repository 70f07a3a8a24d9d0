#include "autodiff/fit.h"
#include "autodiff/latent_path_adjoint.h"
#include "autodiff/loss.h"
#include "autodiff/path_record.h"
#include "autodiff/lr_schedule.h"
#include "core/image_io.h"
#include "core/json_number.h"
#include "core/sampler.h"
#include <nlohmann/json.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace lpt {

namespace {

RenderOptions iteration_options(const LatentModel& model, const FitOptions& o, int width, int height, int iteration) {
    // A new, reproducible set of paths per iteration: resumed fits replay the same ones.
    return RenderOptions::from_scene(model.scene(), width, height, o.spp,
                                     mix64(o.seed * 0x9e3779b97f4a7c15ULL + uint64_t(iteration) + 1));
}

}  // namespace

std::vector<float> toned_sum(const TermFilms<kLatentChannels>& films, ToneCurve tone) {
    std::vector<float> img = films.sum();
    tone_map(tone, img.data(), img.data(), img.size());
    return img;
}

std::vector<float> render_toned(const LatentModel& model, const RenderOptions& options, ToneCurve tone) {
    return toned_sum(render_latent_terms<kLatentChannels>(model.scene(), model.spectra(), model.terms(), options),
                     tone);
}

namespace {

/// The slice of the first raw gradient Adam refuses (NaN, Inf, or a square that overflows).
std::string first_bad_gradient(const ParamStore& ps) {
    const std::vector<float>& g = ps.grad_raw();
    for (size_t i = 0; i < g.size(); ++i) {
        if (std::isfinite(g[i]) && std::isfinite(g[i] * g[i])) continue;
        for (size_t k = 0; k < ps.slice_count(); ++k) {
            const ParamSlice& sl = ps.slice(int(k));
            if (i >= sl.raw_offset && i < sl.raw_offset + sl.raw_size()) return sl.name;
        }
    }
    return "?";
}

/// What the fit will return: the best parameters so far with early stopping, the last ones
/// without (patience 0), with their iteration and smoothed loss.
void record_kept_parameters(FitState& state, const EarlyStopping& stopper, int patience, const std::vector<float>& raw,
                            int it) {
    if (patience == 0) {
        state.best_raw = raw;
        state.best_loss = state.smoothed;
        state.best_iteration = it;
        return;
    }
    if (stopper.improved()) state.best_raw = raw;
    state.best_loss = stopper.best_loss();
    state.best_iteration = stopper.best_iteration();
}

/// Adds λ·Σ v² over slice k's values to `penalty` and 2λ·v to their gradients.
void add_square_penalty(ParamStore& ps, int k, float lambda, double& penalty) {
    const float* v = ps.value(k);
    float* g = ps.grad_value(k);
    for (int c = 0; c < ps.slice(k).channels; ++c) {
        penalty += double(lambda) * v[c] * v[c];
        g[c] += 2.f * lambda * v[c];
    }
}

}  // namespace

double add_emission_decay(ParamStore& ps, float lambda) {
    if (lambda == 0.f) return 0.0;
    double penalty = 0.0;
    for (size_t k = 0; k < ps.slice_count(); ++k)
        if (ps.slice(int(k)).kind == "Le") add_square_penalty(ps, int(k), lambda, penalty);
    return penalty;
}

double add_emitter_response_decay(ParamStore& ps, float lambda) {
    if (lambda == 0.f) return 0.0;
    double penalty = 0.0;
    for (size_t k = 0; k < ps.slice_count(); ++k) {
        const ParamSlice& sl = ps.slice(int(k));
        if (sl.kind != "Le") continue;
        // "<shape id>.Le" -> "<shape id>.La", ".Lc"; the environment has neither
        const std::string shape = sl.name.substr(0, sl.name.size() - 2);
        for (const char* response : {"La", "Lc"}) {
            const int r = ps.find(shape + response);
            if (r >= 0) add_square_penalty(ps, r, lambda, penalty);
        }
    }
    return penalty;
}

float exposure_at(const FitOptions& o, int iteration) {
    return o.exposures.empty() ? 1.f : o.exposures[size_t(iteration) % o.exposures.size()];
}

std::vector<float> exposures_other_than_1(const std::vector<float>& exposures) {
    std::vector<float> out;
    for (float k : exposures)
        if (k != 1.f && std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
    return out;
}

void scale_emission_gradients(ParamStore& ps, float k) {
    for (size_t s = 0; s < ps.slice_count(); ++s) {
        if (ps.slice(int(s)).kind != "Le") continue;
        float* g = ps.grad_value(int(s));
        for (int c = 0; c < ps.slice(int(s)).channels; ++c) g[c] *= k;
    }
}

namespace {

std::string exposure_name(float k) {
    std::ostringstream s;
    s << k;
    return s.str();
}

void check_target(const std::vector<float>& target, size_t n, float exposure) {
    const std::string which = exposure == 1.f ? "target" : "target of exposure " + exposure_name(exposure);
    if (target.size() != n)
        throw std::invalid_argument("fit: " + which + " has " + std::to_string(target.size()) + " values, expected " +
                                    std::to_string(n));
    size_t bad_index = 0;
    if (!check_finite(target.data(), n, &bad_index))
        throw std::invalid_argument("fit: " + which + " value " + std::to_string(bad_index) + " (pixel " +
                                    std::to_string(bad_index / kLatentChannels) + ", channel " +
                                    std::to_string(bad_index % kLatentChannels) + ") is not finite");
}

/// Gives a model whose lights scale_emission scaled the parameters' lights back: now(), or when it
/// goes out of scope (an exception) if not yet. Null: nothing to give back.
class ResyncOnExit {
public:
    explicit ResyncOnExit(LatentModel* model) : m_model(model) {}
    ResyncOnExit(const ResyncOnExit&) = delete;
    ResyncOnExit& operator=(const ResyncOnExit&) = delete;
    ~ResyncOnExit() { now(); }
    void now() {
        if (m_model) m_model->sync();
        m_model = nullptr;
    }

private:
    LatentModel* m_model;
};

/// targets[i] for each position of the exposure cycle; throws naming an exposure without one.
std::vector<const std::vector<float>*> targets_of_cycle(const std::vector<ExposureTarget>& targets, const FitOptions& o,
                                                        size_t n) {
    const std::vector<float> cycle = o.exposures.empty() ? std::vector<float>{1.f} : o.exposures;
    std::vector<const std::vector<float>*> out;
    for (float k : cycle) {
        if (!(k > 0.f) || !std::isfinite(k))
            throw std::invalid_argument("fit: exposure " + exposure_name(k) + " is not a finite number > 0");
        const std::vector<float>* found = nullptr;
        for (const ExposureTarget& t : targets)
            if (t.exposure == k) found = &t.latent;
        if (!found) throw std::invalid_argument("fit: no target for exposure " + exposure_name(k));
        check_target(*found, n, k);
        out.push_back(found);
    }
    return out;
}

}  // namespace

FitState fit_latent(LatentModel& model, const std::vector<float>& target, int width, int height, const FitOptions& o,
                    FitState state, const std::function<bool(const FitRecord&, const FitState&)>& on_iteration) {
    return fit_latent(model, std::vector<ExposureTarget>{{1.f, target}}, width, height, o, std::move(state),
                      on_iteration);
}

FitState fit_latent(LatentModel& model, const std::vector<ExposureTarget>& targets, int width, int height,
                    const FitOptions& o, FitState state,
                    const std::function<bool(const FitRecord&, const FitState&)>& on_iteration) {
    const size_t n = size_t(width) * height * kLatentChannels;
    const std::vector<const std::vector<float>*> cycle = targets_of_cycle(targets, o, n);
    ParamStore& ps = model.params();
    Adam adam(ps.raw().size());
    if (!state.adam.m.empty()) adam.set_state(state.adam);
    CosineWarmRestarts schedule(o.lr, o.lr_period, o.lr_t_mult, o.lr_min);
    EarlyStopping stopper(std::max(1, o.patience), o.min_delta);
    stopper.restore(state.best_loss, state.best_iteration, state.bad_updates);
    if (state.best_raw.empty()) state.best_raw = ps.raw();

    std::vector<float> d_toned(n), d_image(n);
    // Stored paths serve K iterations; a checkpoint falls on a block boundary so that a resumed
    // fit records the same paths from the same parameters as an uninterrupted one.
    const int K = std::max(0, o.reuse_paths);
    const int checkpoint_every =
        K > 0 && o.checkpoint_every > 0 ? (o.checkpoint_every + K - 1) / K * K : o.checkpoint_every;
    std::optional<PathRecords> records;
    auto t0 = std::chrono::steady_clock::now();
    double seconds_before = state.history.empty() ? 0.0 : state.history.back().seconds;
    // A fit that stopped early stays stopped when resumed (killed in its refiner stage, say):
    // its state says so, and one more step would change what it returns.
    const bool stopped = o.patience > 0 && state.bad_updates >= o.patience;
    for (int it = stopped ? o.iterations : state.next_iteration; it < o.iterations; ++it) {
        const RenderOptions ro = iteration_options(model, o, width, height, K > 0 ? it - it % K : it);
        // The lights at this iteration's exposure; the paths do not depend on it, so stored ones serve.
        const float exposure = exposure_at(o, it);
        const std::vector<float>& target = *cycle[size_t(it) % cycle.size()];
        if (exposure != 1.f) model.scale_emission(exposure);
        // an exception below leaves no model with scaled lights behind
        ResyncOnExit resync(exposure != 1.f ? &model : nullptr);
        // Primal: docs/fitting.md (7) on the tone-mapped latent.
        std::vector<float> linear;
        if (K == 0)
            linear = render_latent_terms<kLatentChannels>(model.scene(), model.spectra(), model.terms(), ro).sum();
        else if (it % K == 0 || !records) {
            records.reset();  // free the previous frame first: peak memory stays one frame
            records = record_latent_paths(model, ro, &linear);
        } else linear = replay_forward(model, *records);
        std::vector<float> toned(n);
        tone_map(o.tone, linear.data(), toned.data(), n);
        double loss = huber_loss(toned.data(), target.data(), n, o.huber_delta, d_toned.data());
        tone_map_backward(o.tone, linear.data(), d_toned.data(), d_image.data(), n);
        // Adjoint: path replay with the same options (same random numbers), or of the stored paths.
        ps.zero_grad();
        if (K == 0) backward_latent(model, ro, d_image);
        else replay_backward(model, *records, d_image);
        if (exposure != 1.f) {
            scale_emission_gradients(ps, exposure);
            resync.now();  // the lights as the parameters say, for the decays and the step
        }
        loss += add_emission_decay(ps, o.emission_decay) + add_emitter_response_decay(ps, o.emitter_response_decay);
        ps.backward();
        const float lr = schedule.lr_at(it);
        size_t bad = adam.step(ps.raw().data(), ps.grad_raw().data(), ps.raw().size(), lr);
        if (bad) ++state.skipped_steps;  // the step was refused: parameters and Adam state untouched
        ps.clamp_raw();
        model.sync();

        state.smoothed = state.smoothed < 0 ? loss : o.smoothing * state.smoothed + (1.0 - o.smoothing) * loss;
        bool stop = o.patience > 0 && stopper.update(state.smoothed, it);
        record_kept_parameters(state, stopper, o.patience, ps.raw(), it);
        state.bad_updates = stopper.bad_updates();
        state.next_iteration = it + 1;
        state.adam = adam.state();
        double secs = seconds_before + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        FitRecord rec{it, loss, state.smoothed, lr, secs, bad != 0, bad ? first_bad_gradient(ps) : std::string()};
        state.history.push_back(rec);
        if (checkpoint_every > 0 && !o.checkpoint_dir.empty() && (it + 1) % checkpoint_every == 0)
            save_checkpoint(o.checkpoint_dir, model, state);
        if (on_iteration && !on_iteration(rec, state)) break;
        if (stop) break;
    }
    // Early stopping restores the best parameters for real.
    ps.raw() = state.best_raw;
    ps.update_values();
    model.sync();
    return state;
}

void save_checkpoint(const std::string& dir, const LatentModel& model, const FitState& s) {
    namespace fs = std::filesystem;
    fs::create_directories(dir);
    nlohmann::json j;
    j["next_iteration"] = s.next_iteration;
    j["smoothed"] = s.smoothed;
    j["best_loss"] = s.best_loss;
    j["best_iteration"] = s.best_iteration;
    j["bad_updates"] = s.bad_updates;
    j["skipped_steps"] = s.skipped_steps;
    j["best_raw"] = s.best_raw;
    j["history"] = nlohmann::json::array();
    for (const FitRecord& r : s.history) j["history"].push_back({r.iteration, r.loss, r.smoothed, r.lr, r.seconds});
    // Each file is written atomically; params and Adam state carry the iteration in their names
    // and state.json, written last, names them: a run killed at any point leaves either the old
    // or the new checkpoint complete, never a mix.
    const std::string tag = std::to_string(s.next_iteration);
    j["tag"] = tag;
    write_text_atomic((fs::path(dir) / ("params-" + tag + ".json")).string(), model.params().to_json());
    write_text_atomic((fs::path(dir) / ("adam-" + tag + ".bin")).string(), serialize_adam_state(s.adam));
    write_text_atomic((fs::path(dir) / "state.json").string(), j.dump());
    for (const auto& entry : fs::directory_iterator(dir)) {
        const std::string name = entry.path().filename().string();
        bool ours = name.rfind("params-", 0) == 0 || name.rfind("adam-", 0) == 0;
        if (ours && name != "params-" + tag + ".json" && name != "adam-" + tag + ".bin") fs::remove(entry.path());
    }
}

FitState load_checkpoint(const std::string& dir, LatentModel& model) {
    namespace fs = std::filesystem;
    const std::string state_path = (fs::path(dir) / "state.json").string();
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(read_file(state_path));
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(state_path + ": malformed checkpoint: " + e.what());
    }
    if (!j.is_object()) throw std::runtime_error(state_path + ": malformed checkpoint: expected a JSON object");
    FitState s;
    std::string tag;
    try {
        tag = j.value("tag", std::string());
        s.next_iteration = json_int(j.at("next_iteration"), state_path, "next_iteration", 0);
        s.smoothed = j.at("smoothed");
        s.best_loss = j.at("best_loss");
        s.best_iteration = json_int(j.at("best_iteration"), state_path, "best_iteration", -1);
        s.bad_updates = json_int(j.at("bad_updates"), state_path, "bad_updates", 0);
        s.skipped_steps = json_int(j.at("skipped_steps"), state_path, "skipped_steps", 0);
        s.best_raw = j.at("best_raw").get<std::vector<float>>();
        for (const auto& r : j.at("history"))
            s.history.push_back({json_int(r.at(0), state_path, "history[][0]", 0),
                                 r.at(1).get<double>(),
                                 r.at(2).get<double>(),
                                 r.at(3).get<float>(),
                                 r.at(4).get<double>(),
                                 false,
                                 {}});
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(state_path + ": incomplete checkpoint: " + e.what());
    }
    const std::string params_path = (fs::path(dir) / ("params-" + tag + ".json")).string();
    model.params().load_json(read_file(params_path), params_path);
    if (s.best_raw.size() != model.params().raw().size())
        throw std::runtime_error(state_path + ": best_raw does not match this scene's parameters");
    model.params().update_values();
    model.sync();
    try {
        s.adam = deserialize_adam_state(read_file((fs::path(dir) / ("adam-" + tag + ".bin")).string()));
    } catch (const std::runtime_error& e) {
        throw std::runtime_error((fs::path(dir) / ("adam-" + tag + ".bin")).string() + ": " + e.what());
    }
    return s;
}

}  // namespace lpt
