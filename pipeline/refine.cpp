#include "pipeline/refine.h"
#include "autodiff/loss.h"
#include "core/image_io.h"
#include "core/sampler.h"
#include "integrators/aov.h"
#include "latent/latent.h"
#include "pipeline/emitter_refiner.h"
#include "pipeline/fit_checkpoint.h"
#include "pipeline/fit_folder.h"
#include "pipeline/output_lock.h"
#include "pipeline/paths.h"
#include "pipeline/refiner_augment.h"
#include "pipeline/refiner_io.h"
#include "vae/compensated_encode.h"
#include "vae/lpips.h"
#include "vae/vae.h"
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

/// What decoded latents are judged with and against: the fit's VAE and LPIPS when present, and
/// the RGB reference when the fit encoded one, else the decoded target.
struct Judges {
    std::unique_ptr<Vae> vae;
    std::unique_ptr<Lpips> lpips;
    std::vector<float> ref_rgb;
    bool path_traced = false;  ///< ref_rgb is reference_rgb.exr
};

Judges open_judges(const RefineJob& job, const Image& target, const Reporter& report) {
    const fs::path dir(job.fitdir);
    const VaeSource vae_source = manifest_vae((dir / "fit.json").string());
    Judges j;
    if (vae_present(vae_source)) j.vae = open_vae(vae_source);
    const std::string lpips_dir = default_lpips_dir(job.lpips_dir);
    if (fs::exists(fs::path(lpips_dir) / "lpips_squeeze_v0.1.safetensors")) j.lpips = Lpips::load(lpips_dir);
    if (!j.vae || !j.lpips)
        report.say("note: no " +
                   (j.vae ? "LPIPS weights in " + lpips_dir : "VAE (" + default_vae_dir(vae_source.dir) + ")") +
                   ": refiner trains on latent MSE + SSIM only");
    j.path_traced = fs::exists(dir / "reference_rgb.exr");
    if (j.path_traced)
        j.ref_rgb = read_fit_image((dir / "reference_rgb.exr").string(), 3, 8 * target.width, 8 * target.height).data;
    else if (j.vae) j.ref_rgb = j.vae->decode(target.data, target.width, target.height);
    return j;
}

/// Distances enter scaled by the training view's mean hit distance, so a scene in millimetres and
/// one in metres feed the network the same numbers.
float mean_hit_distance(const RefinerInput& in) {
    double sum = 0;
    int n = 0;
    for (float d : in.distance)
        if (d > 0) sum += d, ++n;
    return n ? float(sum / n) : 1.f;
}

/// RGB metrics of a decoded latent against the reference image (both in [0, 1] display values).
nlohmann::json rgb_metrics(std::vector<float> rgb, const std::vector<float>& ref, int w, int h, const Lpips* lpips) {
    for (float& v : rgb) v = std::clamp(v, 0.f, 1.f);
    nlohmann::json j = {{"rgb_mse_x100", 100.0 * mse_loss(rgb.data(), ref.data(), rgb.size())}};
    if (lpips && w >= Lpips::kMinSize && h >= Lpips::kMinSize) j["rgb_lpips"] = lpips->distance(rgb, ref, w, h);
    return j;
}

double latent_mse(const std::vector<float>& a, const std::vector<float>& b) {
    return mse_loss(a.data(), b.data(), a.size());
}

std::string refiner_csv(const RefinerTrainResult& res) {
    std::ostringstream csv;
    csv << "iteration,loss,smoothed_loss,mse,dssim,lpips,seconds\n";
    for (const RefinerRecord& r : res.history)
        csv << r.iteration << "," << r.loss << "," << r.smoothed << "," << r.mse << "," << r.dssim << "," << r.lpips
            << "," << r.seconds << "\n";
    return csv.str();
}

nlohmann::json training_record(const RefineJob& job, const Refiner& refiner, const RefinerTrainResult& res) {
    const double seconds = res.history.empty() ? 0.0 : res.history.back().seconds;
    nlohmann::json record = {
        {"expansion", job.net.expansion},
        {"norm", refiner.config().instance_norm ? "instance" : "none"},
        {"parameters", refiner.parameter_count()},
        {"iterations", res.history.size()},
        {"best_iteration", res.best_iteration},
        {"seconds", seconds},
        {"seconds_per_iteration", res.history.empty() ? 0.0 : seconds / double(res.history.size())},
        {"crop", job.train.crop},
        {"noise_views", job.noise_views},
        {"augment", to_string(job.augment)},
        {"lr_decay", job.train.cosine_decay ? "cosine" : "none"},
        {"inference_window", refiner.config().tile},
        {"inference_stride", refiner.config().tile > 0 ? inference_stride(refiner.config()) : 0},
        {"lpips_crop", job.train.lpips_crop},
        {"latent_target", job.compensated_target ? "compensated" : "encoded"}};
    if (job.latent_target_block) record["latent_target_block"] = job.latent_target_block;
    if (job.train.input_noise > 0.f) record["input_noise"] = job.train.input_noise;
    if (refiner.config().arch != RefinerArch::Conv) record["arch"] = to_string(refiner.config().arch);
    if (refiner.config().terms) record["inputs"] = "terms";
    if (refiner.config().emitter_cells) record["emitter_cells"] = refiner.config().emitter_cells;
    return record;
}

/// metrics.json: latent MSE of the rendered and refined latents against the target, and with a
/// VAE their decoded RGB errors and the VAE's own round trip; writes decoded_refined.png.
nlohmann::json judge(const fs::path& dir, const RefinerInput& in, const std::vector<float>& refined,
                     const Image& target, const Judges& j) {
    nlohmann::json m = {{"rendered", {{"latent_mse", latent_mse(in.latent, target.data)}}},
                        {"refined", {{"latent_mse", latent_mse(refined, target.data)}}}};
    if (!j.vae || j.ref_rgb.empty()) return m;
    const int w = in.width, h = in.height, iw = 8 * w, ih = 8 * h;
    std::vector<float> dec_rendered = j.vae->decode(in.latent, w, h), dec_refined = j.vae->decode(refined, w, h);
    m["rendered"].update(rgb_metrics(dec_rendered, j.ref_rgb, iw, ih, j.lpips.get()));
    m["refined"].update(rgb_metrics(dec_refined, j.ref_rgb, iw, ih, j.lpips.get()));
    if (j.path_traced)
        m["vae_roundtrip"] =
            rgb_metrics(j.vae->decode(j.vae->encode(j.ref_rgb, iw, ih), w, h), j.ref_rgb, iw, ih, j.lpips.get());
    m["reference"] = j.path_traced ? "reference_rgb.exr (path-traced RGB)" : "decoded target.exr";
    write_png_display((dir / "decoded_refined.png").string(), Image{iw, ih, 3, dec_refined, {}});
    return m;
}

/// Seed of the fit's k-th extra render of the training view: hashed, so that it is none of the
/// small seeds (fit seed + 1, edit seed + frame) that the fit's latent and edited frames use.
uint64_t noise_view_seed(uint64_t fit_seed, int k) { return mix64(fit_seed ^ mix64(0x6e6f697365ull + uint64_t(k))); }

/// The spp of the fit's latent.exr, which renders made again for `option` match.
int fit_final_spp(const RefineJob& job, const FitFolder& fit, const std::string& option) {
    const int spp = fit.manifest.value("stage1", nlohmann::json::object()).value("final_spp", 0);
    if (spp <= 0)
        throw std::runtime_error((fs::path(job.fitdir) / "fit.json").string() +
                                 ": field 'stage1.final_spp' missing or not positive (needed for " + option + ")");
    return spp;
}

/// The seed stage 1 ran with (fit.json); extra training views take seeds made from it.
uint64_t fit_seed(const FitFolder& fit) { return fit.manifest.value("seed", uint64_t(0)); }

/// The fit's own view first, then job.noise_views − 1 renders of the same camera with other seeds.
std::vector<RefinerInput> noise_views(const RefineJob& job, const FitFolder& fit, RefinerInput fit_view,
                                      const Reporter& report) {
    std::vector<RefinerInput> views;
    views.push_back(std::move(fit_view));
    if (job.noise_views <= 1) return views;
    const int spp = fit_final_spp(job, fit, "--noise-views");
    report.say("[refine] rendering " + std::to_string(job.noise_views - 1) + " more views of the training view at " +
               std::to_string(spp) + " spp");
    const int w = views[0].width, h = views[0].height;
    // Emitter cells are the view's geometry, not a sample: every noise view shares the training view's.
    RefinerConfig without_cells = job.net;
    without_cells.emitter_cells = 0;
    for (int k = 1; k < job.noise_views; ++k) {
        const uint64_t seed = noise_view_seed(fit_seed(fit), k);
        views.push_back(fit_refiner_view(fit, without_cells, w, h, spp, seed));
        views.back().emitter = views[0].emitter;
    }
    return views;
}

/// Throws unless the fit has a path-traced reference and a VAE, which `option` needs.
void require_reference(const RefineJob& job, const Judges& judges, const std::string& option) {
    if (!judges.path_traced || !judges.vae)
        throw std::runtime_error((fs::path(job.fitdir) / "reference_rgb.exr").string() + ": " + option +
                                 " needs the fit's path-traced reference and its VAE " +
                                 (judges.path_traced ? "(no VAE found)" : "(missing: fit with --encode)"));
}

/// The latent a training view's reference `rgb` is learnt as: its encoding, or with
/// job.compensated_target its compensated encoding.
std::vector<float> latent_target(const RefineJob& job, const Vae& vae, const std::vector<float>& rgb, int width,
                                 int height) {
    if (!job.compensated_target) return vae.encode(rgb, width, height);
    const int block = job.latent_target_block;
    if (block > 0 && (width % block || height % block))
        throw std::invalid_argument("refine --latent-target-block (fit --refiner-latent-target-block) " +
                                    std::to_string(block) + " does not divide the " + std::to_string(width) + "x" +
                                    std::to_string(height) + " reference into whole blocks");
    return encode_compensated(vae, rgb, width, height, block);
}

/// Puts the fit's scene camera back when a scope ends, however it ends.
struct CameraRestore {
    Scene& scene;
    Camera saved;
    explicit CameraRestore(Scene& s) : scene(s), saved(s.camera) {}
    ~CameraRestore() { scene.camera = saved; }
};

/// job.augment shift: the training view rendered again through the film moved by each of
/// film_shifts() (seeds of their own, the fit's final spp), cropped to the latent cells the
/// reference covers, against the reference moved the same way and encoded.
void add_film_shift_examples(const RefineJob& job, const FitFolder& fit, const Judges& judges, int w, int h,
                             std::vector<RefinerExample>& examples, const Reporter& report) {
    require_reference(job, judges, "--refiner-augment shift");
    const int spp = fit_final_spp(job, fit, "--refiner-augment shift");
    const std::vector<FilmShift> shifts = film_shifts();
    report.say("[refine] " + std::to_string(shifts.size()) +
               " augmented views (shift): the film moved by half a latent pixel, rendered and their references "
               "encoded");
    for (size_t i = 0; i < shifts.size(); ++i) {
        const FilmShift s = shifts[i];
        const int cw = w - (s.x > 0 ? 1 : 0), ch = h - (s.y > 0 ? 1 : 0);
        RefinerInput view;
        {
            const CameraRestore restore(*fit.scene);
            fit.scene->camera = film_shifted(restore.saved, float(s.x) / float(8 * w), float(s.y) / float(8 * h));
            view = fit_refiner_view(fit, job.net, w, h, spp, noise_view_seed(fit_seed(fit), 1000 + int(i)));
        }
        std::vector<float> rgb = crop_image(judges.ref_rgb, 8 * w, 3, s.x, s.y, 8 * cw, 8 * ch);
        std::vector<float> target = latent_target(job, *judges.vae, rgb, 8 * cw, 8 * ch);
        examples.push_back({crop_view(view, 0, 0, cw, ch), std::move(target), std::move(rgb)});
    }
}

/// The training examples: every noise view against the target (target.exr, or with
/// job.compensated_target the reference's compensated encoding), then (job.augment) every noise
/// view moved by each other transform, against the reference image moved the same way and
/// encoded again (docs/refiner.md "Augmentation").
std::vector<RefinerExample> training_examples(const RefineJob& job, const FitFolder& fit,
                                              const std::vector<RefinerInput>& views, const Image& target,
                                              const Judges& judges, const Reporter& report) {
    const int iw = 8 * target.width, ih = 8 * target.height;
    std::vector<float> view_target = target.data;
    if (job.compensated_target) {
        require_reference(job, judges, "refine --latent-target compensated (fit --refiner-latent-target)");
        report.say("[refine] target: the reference encoded with the decoder's low-frequency bias compensated");
        view_target = latent_target(job, *judges.vae, judges.ref_rgb, iw, ih);
    }
    std::vector<RefinerExample> examples;
    for (const RefinerInput& v : views) examples.push_back({v, view_target, judges.ref_rgb});
    if (job.augment == RefinerAugment::Shift) {
        add_film_shift_examples(job, fit, judges, target.width, target.height, examples, report);
        return examples;
    }
    const std::vector<ViewTransform> moves = augment_transforms(job.augment);
    if (moves.size() == 1) return examples;
    require_reference(job, judges, "--refiner-augment " + to_string(job.augment));
    report.say("[refine] " + std::to_string(moves.size() - 1) + " augmented views (" + to_string(job.augment) +
               "): encoding their references");
    const Vec3f right = mirror_plane_normal(fit.scene->camera);
    for (size_t m = 1; m < moves.size(); ++m) {
        std::vector<float> rgb = transform_image(judges.ref_rgb, iw, ih, 3, moves[m]);
        const bool swap = moves[m].swaps_axes();
        std::vector<float> moved_target = latent_target(job, *judges.vae, rgb, swap ? ih : iw, swap ? iw : ih);
        for (const RefinerInput& v : views) examples.push_back({transform_view(v, moves[m], right), moved_target, rgb});
    }
    return examples;
}

std::string refine_status(const RefinerRecord& r) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "loss %.4f (smoothed %.4f; mse %.4f dssim %.4f lpips %.4f)", r.loss, r.smoothed,
                  r.mse, r.dssim, r.lpips);
    return buf;
}

/// The files a refine job trains: the main refiner's, or (job.emitters) the emitter refiner's.
struct RefinerFiles {
    fs::path weights, checkpoint, loss;
};

RefinerFiles refiner_files(const RefineJob& job) {
    const fs::path dir(job.fitdir);
    if (!job.emitters) return {dir / "refiner.pt", dir / "refiner_checkpoint.pt", dir / "refiner_loss.csv"};
    return {dir / kEmitterRefinerFile, dir / kEmitterRefinerCheckpoint, dir / kEmitterRefinerLoss};
}

}  // namespace

void remove_refiners(const std::string& dir) {
    remove_emitter_refiner(dir);
    for (const char* name : {"refiner.pt", "refiner_checkpoint.pt", "refiner_checkpoint.json", "refiner_loss.csv",
                             "latent_refined.exr", "decoded_refined.png", "metrics.json"})
        fs::remove(fs::path(dir) / name);
}

namespace {

/// metrics.json as it is, or an empty object when there is none. One that is not a JSON object
/// is an error when `strict` (an emitter refiner adds its record to the main refiner's cells,
/// which would be lost); the main refiner writes the file anew and reads it as empty.
nlohmann::json existing_metrics(const fs::path& dir, bool strict) {
    const fs::path path = dir / "metrics.json";
    if (!fs::exists(path)) return nlohmann::json::object();
    nlohmann::json m = nlohmann::json::parse(read_file(path.string()), nullptr, false);
    if (m.is_object()) return m;
    if (strict)
        throw std::runtime_error(path.string() +
                                 ": not a JSON object; refine --emitters adds its record to the main "
                                 "refiner's metrics: train that again (latentpt refine)");
    return nlohmann::json::object();
}

/// An emitter refiner is trained beside refiner.pt, which must be there and read what it reads.
void require_main_refiner(const RefineJob& job) {
    const fs::path pt = fs::path(job.fitdir) / "refiner.pt";
    if (!fs::exists(pt))
        throw std::runtime_error(pt.string() +
                                 ": not found; refine --emitters trains a second refiner beside the "
                                 "main one: train that first (latentpt refine, or fit)");
    check_emitter_refiner_inputs(Refiner::load(pt.string())->config(), job.net,
                                 (fs::path(job.fitdir) / kEmitterRefinerFile).string());
    existing_metrics(job.fitdir, true);  // before training: its record goes there
}

/// The refiner's inference window: its training crop, when InstanceNorm makes the output depend
/// on the statistics of what the network sees and the crop is smaller than the view; else 0
/// (the whole view, which is then also what training saw).
int inference_window(const RefineJob& job, const RefinerInput& in) {
    const int crop = job.train.crop;
    if (!job.windowed_inference || !job.net.instance_norm || crop <= 0) return 0;
    return crop < in.width || crop < in.height ? crop : 0;
}

/// The kept weights must refine their own training view: --lr 1e30 took one step to weights
/// whose output's latent MSE was 4e61 (every later step refused), and wrote them with exit 0.
/// A trained refiner lowers its input's error there; 100 times it is far beyond any that learnt.
void require_trained(const RefineJob& job, const RefinerInput& in, const std::vector<float>& refined,
                     const Image& target) {
    double before = 0, after = 0;
    for (size_t i = 0; i < refined.size(); ++i) {
        before += double(in.latent[i] - target.data[i]) * double(in.latent[i] - target.data[i]);
        after += double(refined[i] - target.data[i]) * double(refined[i] - target.data[i]);
    }
    if (std::isfinite(after) && after <= 100.0 * std::max(before, 1e-12 * double(refined.size()))) return;
    char buf[160];
    std::snprintf(buf, sizeof buf, "latent squared error %.3g against its input's %.3g", after, before);
    throw std::runtime_error(job.fitdir + ": the trained refiner ruins its own training view (" + buf +
                             "): a learning rate too large?; nothing written");
}

/// What a trained refiner leaves in the fit folder: its weights and loss history, and for the
/// main refiner the refined training view and metrics.json (in s.metrics); an emitter refiner's
/// record is added to metrics.json, whose other records stay.
void write_results(const RefineJob& job, const RefinerFiles& files, const Refiner& refiner, const RefinerInput& in,
                   const Image& target, const Judges& judges, RefineSummary& s) {
    const fs::path dir(job.fitdir);
    const std::vector<float> refined = refiner.refine(in);  // either refiner's, judged alike
    require_trained(job, in, refined, target);
    refiner.save(files.weights.string());
    write_text_atomic(files.loss.string(), refiner_csv(s.result));
    const nlohmann::json before = existing_metrics(dir, job.emitters);
    if (job.emitters) {
        // The training view sees every emitter as in training, where the main refiner's output
        // stands: its refined latent and metrics are unchanged.
        s.metrics = before;
        s.metrics["emitter_refiner"] = training_record(job, refiner, s.result);
    } else {
        write_latent((dir / "latent_refined.exr").string(), in.width, in.height, refined);
        s.metrics = judge(dir, in, refined, target, judges);
        s.metrics["refiner"] = training_record(job, refiner, s.result);
        if (before.contains("emitter_refiner") && fs::exists(dir / kEmitterRefinerFile))
            s.metrics["emitter_refiner"] = before["emitter_refiner"];
        s.decoded = judges.vae != nullptr && !judges.ref_rgb.empty();
    }
    write_text_atomic((dir / "metrics.json").string(), s.metrics.dump(2));
}

}  // namespace

void validate(const RefineJob& job) {
    auto require = [](bool ok, const char* option, const std::string& range, double value) {
        if (!ok) {
            char v[32];
            std::snprintf(v, sizeof v, "%g", value);
            throw std::invalid_argument(std::string("refine --") + option + " (fit --refiner-" + option + ") must be " +
                                        range + ", got " + v);
        }
    };
    const RefinerTrainOptions& t = job.train;
    const RefinerConfig& n = job.net;
    require(t.iterations > 0, "iterations", "> 0", t.iterations);
    // 64 is 4x the default's width; 10^5 ended in a 26-line torch allocation trace
    require(n.expansion > 0 && n.expansion <= 64, "expansion", "in [1, 64]", n.expansion);
    require(t.crop >= 0, "crop", ">= 0", t.crop);
    require(job.window_stride > 0, "window-stride", "> 0", job.window_stride);
    require(t.crop == 0 || job.window_stride <= t.crop, "window-stride", "at most --crop (every pixel in a window)",
            job.window_stride);
    require(t.lpips_crop >= 0, "lpips-crop", ">= 0", t.lpips_crop);
    require(t.lr > 0 && std::isfinite(t.lr), "lr", "> 0", t.lr);
    require(t.patience >= 0, "patience", ">= 0", t.patience);
    require(t.w_mse >= 0 && std::isfinite(t.w_mse), "w-mse", ">= 0", t.w_mse);
    require(t.w_ssim >= 0 && std::isfinite(t.w_ssim), "w-ssim", ">= 0", t.w_ssim);
    require(t.w_lpips >= 0 && std::isfinite(t.w_lpips), "w-lpips", ">= 0", t.w_lpips);
    require(t.w_mse + t.w_ssim + t.w_lpips > 0, "w-mse", "> 0 when --w-ssim and --w-lpips are 0 (no loss)", t.w_mse);
    require(n.squash > 0 && std::isfinite(n.squash), "squash", "> 0", n.squash);
    require(n.dropout >= 0 && n.dropout <= 0.99f, "dropout", "in [0, 0.99]", n.dropout);
    require(job.noise_views > 0 && job.noise_views <= 64, "noise-views", "in [1, 64]", job.noise_views);
    require(t.input_noise >= 0 && std::isfinite(t.input_noise), "input-noise", ">= 0", t.input_noise);
    // the terms carry the latent's render noise too; read clean, the body could still key on it
    require(t.input_noise == 0 || !n.terms, "input-noise", "0 with --inputs terms (the terms are read without noise)",
            t.input_noise);
    require(n.emitter_cells >= 0 && n.emitter_cells <= 8, "emitter-cells", "in [0, 8]", n.emitter_cells);
    // transform_view would have to reorder the sub-cells inside each pixel; shift renders them anew
    require(n.emitter_cells == 0 || job.augment == RefinerAugment::None || job.augment == RefinerAugment::Shift,
            "emitter-cells", "0 with --augment mirror or dihedral", n.emitter_cells);
    require(t.checkpoint_every >= 0, "checkpoint-every", ">= 0", t.checkpoint_every);
    require(job.latent_target_block >= 0, "latent-target-block", ">= 0", job.latent_target_block);
    require(job.latent_target_block == 0 || job.compensated_target, "latent-target-block",
            "0 unless the latent target is compensated", job.latent_target_block);
}

RefineSummary run_refine(const RefineJob& job, const Reporter& report) {
    validate(job);
    const fs::path dir(job.fitdir);
    if (!fs::is_directory(dir))
        throw std::runtime_error(job.fitdir + ": not a folder (expected a fit folder made by latentpt fit)");
    const OutputLock lock(job.fitdir);
    RefinerInput in = load_refiner_input((dir / "latent.exr").string(), (dir / "aov.exr").string());
    if (job.net.terms) in.terms = load_refiner_terms(job.fitdir, in.width, in.height);
    const Image target = read_fit_image((dir / "target.exr").string(), kLatentChannels, in.width, in.height);
    const Judges judges = open_judges(job, target, report);
    const RefinerFiles files = refiner_files(job);
    if (job.emitters) require_main_refiner(job);

    RefinerConfig cfg = job.net;
    cfg.latent_channels = kLatentChannels;
    cfg.distance_scale = mean_hit_distance(in);
    cfg.tile = inference_window(job, in);
    cfg.window_stride = cfg.tile > 0 ? job.window_stride : 0;
    auto refiner = Refiner::create(cfg, job.train.seed);
    RefinerTrainOptions o = job.train;
    o.checkpoint_path = files.checkpoint.string();
    o.resume = prepare_refiner_checkpoint(o.checkpoint_path, stage2_settings(job),
                                          job.resume && fs::exists(o.checkpoint_path), job.restart_if_changed);
    bool cancelled = false;
    std::set<std::string> reported;  // once per weight
    auto on_iteration = [&](const RefinerRecord& r) {
        if (r.refused && reported.insert(r.refused_parameter).second)
            report.say("warning: refiner iteration " + std::to_string(r.iteration) + ": " +
                       (r.refused_parameter == "loss" ? std::string("the loss")
                                                      : "the gradient of '" + r.refused_parameter + "'") +
                       " is not finite: step refused, weights and Adam state kept");
        StageProgress p;
        p.stage = "refine";
        p.step = r.iteration + 1;
        p.total = o.iterations;
        p.seconds = r.seconds;
        p.status = refine_status(r);
        cancelled = !report.step(p);
        return !cancelled;
    };
    RefineSummary s;
    // The fitted scene (a load of the scene and its BVH) only when extra views or emitter cells need it.
    const bool needs_fit = job.noise_views > 1 || job.augment != RefinerAugment::None || job.net.emitter_cells > 0;
    const FitFolder fit = needs_fit ? load_fit_folder(job.fitdir, {}, job.sampler) : FitFolder{};
    if (job.net.emitter_cells)
        in.emitter = render_emitter_cells(*fit.scene, in.width, in.height, job.net.emitter_cells);
    const std::vector<RefinerExample> examples =
        training_examples(job, fit, noise_views(job, fit, in, report), target, judges, report);
    if (examples.size() > 1 && o.patience > 0)
        report.say("note: " + std::to_string(examples.size()) + " training views with early stopping (patience " +
                   std::to_string(o.patience) +
                   "): the smoothed loss of several views improves more slowly than its noise late in the "
                   "schedule, which stopped such runs at ~70 % of their steps; patience 0 (fit --refiner-patience 0, "
                   "refine --patience 0) runs every step (docs/refiner.md "
                   "\"Augmentation\")");
    s.result = refiner->train(examples, judges.vae.get(), judges.lpips.get(), o, on_iteration);
    if (cancelled) throw Cancelled("refine");
    // Every step refused (a NaN in the loss weights' reach): the weights were never trained, and
    // were written with exit 0. (A resumed history reads as taken: it holds no refusals.)
    const std::vector<RefinerRecord>& h = s.result.history;
    if (!h.empty() && std::all_of(h.begin(), h.end(), [](const RefinerRecord& r) { return r.refused; }))
        throw std::runtime_error(job.fitdir +
                                 ": the refiner refused every step (its loss or a gradient was not finite); nothing "
                                 "written: check --lr and the loss weights");
    char best[96];
    std::snprintf(best, sizeof best, "[refine] best smoothed loss %.5f at iteration %d", s.result.best_loss,
                  s.result.best_iteration);
    report.say(best);
    write_results(job, files, *refiner, in, target, judges, s);
    return s;
}

}  // namespace lpt::pipeline
