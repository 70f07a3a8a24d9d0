#include "pipeline/edit.h"
#include "autodiff/fit.h"
#include "autodiff/loss.h"
#include "core/fingerprint.h"
#include "core/image_io.h"
#include "pipeline/edit_session.h"
#include "pipeline/emitter_refiner.h"
#include "pipeline/fit_folder.h"
#include "pipeline/frame_cache.h"
#include "pipeline/paths.h"
#include "pipeline/reference.h"
#include "pipeline/refiner_io.h"
#include "vae/lpips.h"
#include "vae/ssim.h"
#include "vae/vae.h"
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <utility>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

const char* const kMetricColumns = "latent_mse,latent_psnr,latent_dssim,rgb_mse_x100,rgb_ssim,rgb_lpips";

/// What the frames are decoded and judged with; each is optional (the refiner is the session's).
struct Tools {
    std::unique_ptr<Vae> vae;
    std::unique_ptr<Lpips> lpips;
    std::string encoder;  ///< with --reference: the VAE's vae_encoder_fingerprint (cached latents record it)
};

Tools open_tools(const EditJob& job, const EditSession& session, const Reporter& report) {
    const FitFolder& fit = session.fit();
    const bool have_vae = vae_present(fit.vae);
    if (job.reference && !have_vae)
        throw std::runtime_error("--reference needs the fit's VAE to encode references; not found: " +
                                 default_vae_dir(fit.vae.dir));
    if (!have_vae)
        report.say("note: the fit's VAE is not here (" + default_vae_dir(fit.vae.dir) + "): writing latents only");
    Tools t;
    // Stage 2, when the fit trained one: every frame is refined from its latent and AOVs.
    if (!session.has_refiner())
        report.say("note: " + (fs::path(job.fitdir) / "refiner.pt").string() + " not found: frames are not refined");
    if (have_vae) t.vae = open_vae(fit.vae);
    if (job.reference && have_vae) {
        t.encoder = vae_encoder_fingerprint(fit.vae);
        const std::string lpips_dir = default_lpips_dir("");
        if (fs::exists(fs::path(lpips_dir) / "lpips_squeeze_v0.1.safetensors")) t.lpips = Lpips::load(lpips_dir);
        else report.say("note: no LPIPS weights at " + lpips_dir + ": rgb_lpips left empty");
    }
    return t;
}

std::string metrics_header(bool refined) {
    std::string header = std::string("frame,t,") + kMetricColumns;
    if (!refined) return header;
    const std::string c = kMetricColumns;
    for (size_t p = 0, q; p <= c.size(); p = q + 1) {
        q = c.find(',', p);
        if (q == std::string::npos) q = c.size();
        header += ",refined_" + c.substr(p, q - p);
    }
    return header;
}

/// One frame's errors against the encoded reference (docs/metrics.md): latent MSE, PSNR over the
/// data range 6, D-SSIM = 1 − SSIM (range 6); the latent's decoded RGB `rgb` (empty without a VAE;
/// clamped here to [0, 1]) MSE × 100, SSIM, LPIPS against the display-mapped reference. Empty where
/// the image is below a metric's size.
std::string frame_metrics(const std::vector<float>& latent, std::vector<float> rgb, const std::vector<float>& ref,
                          const std::vector<float>& ref_rgb, int w, int h, const Tools& t) {
    const double mse = mse_loss(latent.data(), ref.data(), ref.size());
    std::ostringstream o;
    o << "," << mse << "," << 10.0 * std::log10(36.0 / std::max(mse, 1e-12)) << ",";  // data range 6 (±3)
    if (w >= kSsimWindow && h >= kSsimWindow)
        o << 1.0 - ssim(latent.data(), ref.data(), w, h, kLatentChannels, kLatentDataRange);
    o << ",";
    if (rgb.empty()) {
        o << ",,";
        return o.str();
    }
    for (float& v : rgb) v = std::clamp(v, 0.f, 1.f);
    o << 100.0 * mse_loss(rgb.data(), ref_rgb.data(), rgb.size()) << ",";
    if (8 * w >= kSsimWindow && 8 * h >= kSsimWindow) o << ssim(rgb.data(), ref_rgb.data(), 8 * w, 8 * h, 3, 1.0);
    o << ",";
    if (t.lpips && 8 * w >= Lpips::kMinSize && 8 * h >= Lpips::kMinSize)
        o << t.lpips->distance(rgb, ref_rgb, 8 * w, 8 * h);
    return o.str();
}

/// The encoded reference of frame `index` and its display RGB. The edited scene file is not on
/// disk: path trace this Scene directly, or take the frame from the cache (experiments compare
/// several fits on one sequence). An unedited frame (without -D overrides) is the training view:
/// it is cached under the key `fit --reference-cache` uses, so every sequence's unedited frames
/// and the fits share one trace. An edited frame is traced with its own seed (edited_frame_seed).
std::vector<float> frame_reference(const EditJob& job, const FitFolder& fit, const Tools& t, int index,
                                   const std::string& frame, bool unedited, const std::string& stem, int w, int h,
                                   std::vector<float>& ref_rgb) {
    const uint64_t seed = unedited ? job.ref_seed : edited_frame_seed(job.ref_seed, index);
    std::string cached;
    if (!job.reference_cache.empty())
        cached = (fs::path(job.reference_cache) /
                  ((unedited ? training_reference_key(8 * w, 8 * h, job.ref_spp, fit.ref_tone)
                             : edited_frame_reference_key(fs::path(job.edits).stem().string(), 8 * w, 8 * h,
                                                          job.ref_spp, fit.ref_tone, frame)) +
                   reference_seed_suffix(job.ref_seed)))
                     .string();
    const std::string source = unedited ? reference_source(*fit.scene, fit.defines)
                                        : reference_source(*fit.scene, fit.defines, job.edits, index);
    return cached_encoded_reference(*fit.scene, 8 * w, 8 * h, job.ref_spp, seed, fit.ref_tone, *t.vae, cached, source,
                                    t.encoder, stem + "_reference.png", ref_rgb);
}

/// Whether frame i shows the training view: the scene as fitted, without -D overrides.
bool shows_training_view(const EditJob& job, const EditSession& session, int i) {
    return session.unedited(i) && job.defines.empty();
}

/// Renders, refines and decodes frame `i` into the files `stem` + suffix; returns their suffixes
/// and the frame's scores (empty without job.reference).
CachedFrame render_frame(const EditJob& job, EditSession& session, const Tools& t, int i, int w, int h,
                         const std::string& stem, const std::string& name) {
    const FrameLatents f = session.frame(i, job.spp, job.seed, w, h);
    const bool refiner = session.has_refiner();
    const std::vector<float>&latent = f.latent, &refined = f.refined;
    CachedFrame frame;
    write_latent(stem + "_latent.exr", w, h, latent);
    frame.suffixes.push_back("_latent.exr");
    if (refiner) {
        write_refiner_aovs(stem + "_aov.exr", f.view);
        write_latent(stem + "_refined.exr", w, h, refined);
        frame.suffixes.insert(frame.suffixes.end(), {"_aov.exr", "_refined.exr"});
    }
    // Each latent is decoded once (~5 s at 1024² on 2 cores): the picture and the scores read it.
    std::vector<float> rgb, refined_rgb;
    if (t.vae) {
        // frame_NNNN.png is the result (refined when there is a refiner); _rendered.png the unrefined one.
        rgb = t.vae->decode(latent, w, h);
        write_png_display(stem + (refiner ? "_rendered.png" : ".png"), Image{8 * w, 8 * h, 3, rgb, {}});
        frame.suffixes.push_back(refiner ? "_rendered.png" : ".png");
        if (refiner) {
            refined_rgb = t.vae->decode(refined, w, h);
            write_png_display(stem + ".png", Image{8 * w, 8 * h, 3, refined_rgb, {}});
            frame.suffixes.push_back(".png");
        }
    }
    if (!job.reference) return frame;
    std::vector<float> ref_rgb;
    const std::vector<float> ref =
        frame_reference(job, session.fit(), t, i, name, shows_training_view(job, session, i), stem, w, h, ref_rgb);
    frame.suffixes.push_back("_reference.png");
    frame.scores = frame_metrics(latent, std::move(rgb), ref, ref_rgb, w, h, t);
    if (refiner) frame.scores += frame_metrics(refined, std::move(refined_rgb), ref, ref_rgb, w, h, t);
    return frame;
}

/// Frame i's metrics row (empty without job.reference). With job.frame_cache a frame that shows
/// the training view is rendered once for every sequence: taken from the cache when another job
/// kept it there under `training_view_key`, else rendered and kept.
std::string frame_row(const EditJob& job, EditSession& session, const Tools& t, int i, int w, int h,
                      const fs::path& out, const std::string& training_view_key) {
    char name[64];
    std::snprintf(name, sizeof name, "frame_%04d", i);
    const std::string stem = (out / name).string();
    // What an earlier run made of this frame goes first: made with a refiner or a VAE this run
    // lacks, its _refined.exr or pictures would otherwise stay beside the new frame's files.
    for (const char* suffix : {"_latent.exr", "_aov.exr", "_refined.exr", "_rendered.png", ".png", "_reference.png"})
        fs::remove(stem + suffix);
    // only with a VAE: an entry kept without one has no pictures for a job that has it
    const bool shared = !job.frame_cache.empty() && t.vae && shows_training_view(job, session, i);
    std::optional<std::string> scores;
    if (shared) scores = take_cached_frame(job.frame_cache, training_view_key, name, stem);
    if (!scores) {
        const CachedFrame frame = render_frame(job, session, t, i, w, h, stem, name);
        if (shared) keep_cached_frame(job.frame_cache, training_view_key, name, stem, frame);
        scores = frame.scores;
    }
    if (!job.reference) return {};
    std::ostringstream row;
    row << i << "," << session.time(i) << *scores;
    return row.str();
}

/// The fit folder's files a frame depends on (manifest, parameters, refiners), into a fingerprint.
Fingerprint fit_files(const EditJob& job) {
    Fingerprint fingerprint;
    for (const char* file : {"fit.json", "params.json", "refiner.pt"}) {
        const fs::path p = fs::path(job.fitdir) / file;
        fingerprint.add(fs::exists(p) ? read_file(p.string()) : std::string("absent"));
    }
    const fs::path emitters = fs::path(job.fitdir) / kEmitterRefinerFile;
    if (fs::exists(emitters))
        fingerprint.add(read_file(emitters.string()));  // only then: other folders keep their keys
    return fingerprint;
}

/// `fit` and the edit file; with `with_edits` false the training view's stand-in for it (a frame
/// that shows the training view does not depend on the edit file).
Fingerprint and_edits(Fingerprint fit, const EditJob& job, bool with_edits) {
    fit.add(with_edits ? read_file(job.edits) : std::string("the training view, in any sequence"));
    return fit;
}

/// What a frame's files depend on besides its index: `files` (and_edits of fit_files, read once
/// the session had loaded them) and the render settings, as an FNV-1a hash. frame_NNNN.done starts
/// with it, so --resume skips a frame only if the same fit and settings made it (a refitted fit,
/// rerun by a workflow, renders its frames again). A frame that shows the training view does not
/// depend on the edit file: its name in the frame cache leaves the file out.
std::string frame_hash(const EditJob& job, const EditSession& session, const Tools& tools, Fingerprint fingerprint) {
    auto add = [&fingerprint](const std::string& text) { fingerprint.add(text); };
    for (const auto& [key, value] : job.defines) add(key + "=" + value);
    if (job.sampler) add(std::string("sampler=") + sampler_name(*job.sampler));  // absent: keys as before
    add(std::to_string(job.width) + "x" + std::to_string(job.height) + " spp " + std::to_string(job.spp) + " seed " +
        std::to_string(job.seed) + " reference " + std::to_string(job.reference) + " " + std::to_string(job.ref_spp) +
        reference_seed_suffix(job.ref_seed));     // empty for the default seed: keys as before
    if (job.reference) add(kEditedFrameSeedTag);  // edited frames' references changed seeds: score them again
    // scores made without LPIPS weights leave its cell empty, which means would quietly skip:
    // weights installed later score those frames again (absent: keys as before)
    if (job.reference && !tools.lpips) add("scored without LPIPS");
    // Edited frames show looks for what the training view does not (docs/edits.md). The rules
    // that decide what that is have changed between versions (sessions 41, 42, 49, 50), so the
    // key names the set itself, not only that there is one: an older frame made under other
    // rules is rendered again.
    const std::string looks = session.unseen_emitters().key();
    if (!looks.empty()) add("looks for: " + looks);
    return fingerprint.hex();
}

/// The first line of frame_NNNN.done.
std::string frame_key(const EditJob& job, const EditSession& session, const Tools& tools, const Fingerprint& files) {
    return "key " + frame_hash(job, session, tools, files);
}

/// The metrics row of a finished frame whose .done carries `key`; nullopt when it was made from
/// another fit or settings (or before keys were written).
std::optional<std::string> finished_row(const fs::path& done, const std::string& key) {
    const std::string text = read_file(done.string());
    const size_t eol = text.find('\n');
    if (eol == std::string::npos || text.compare(0, eol, key) != 0) return std::nullopt;
    return text.substr(eol + 1);
}

}  // namespace

int render_edits(const EditJob& job, const Reporter& report) {
    // The CLI checks these; Python's render_edits does not (spp 0 rendered black frames).
    if (job.spp < 1) throw std::invalid_argument("edit spp must be > 0, got " + std::to_string(job.spp));
    if (job.reference && job.ref_spp < 1)
        throw std::invalid_argument("edit ref_spp must be > 0, got " + std::to_string(job.ref_spp));
    if (job.width < 0 || job.height < 0)
        throw std::invalid_argument("edit resolution must not be negative, got " + std::to_string(job.width) + "x" +
                                    std::to_string(job.height));
    if (!fs::is_directory(job.fitdir))
        throw std::runtime_error(job.fitdir + ": --edit needs a fit folder (made by latentpt fit)");
    if (job.out.empty() || (fs::exists(job.out) && !fs::is_directory(job.out)))
        throw std::invalid_argument("render --edit --out '" + job.out + "': not a folder");
    // The frames' key hashes the fit's files as read around the session's loading of them: a fit
    // or refine writing there meanwhile would give frames of the old files the new files' key,
    // which --resume would then keep.
    const Fingerprint before = and_edits(fit_files(job), job, true);
    EditSession session(job.fitdir, job.edits, job.defines, job.sampler);
    const Fingerprint fit = fit_files(job);
    const Fingerprint files = and_edits(fit, job, true), files_without_edits = and_edits(fit, job, false);
    if (files.hex() != before.hex())
        throw std::runtime_error(job.fitdir +
                                 ": its files changed while this render loaded them (a fit or refine "
                                 "writing there?): run again once it has finished");
    const int w = job.width > 0 ? job.width : session.latent_width();
    const int h = job.height > 0 ? job.height : session.latent_height();
    const Tools tools = open_tools(job, session, report);
    for (int shape : session.unseen_emitters().shapes())
        report.say("note: the training view does not show emitter '" + session.fit().scene->shapes[shape].id +
                   "': frames show it in its display colour (docs/edits.md)");
    if (session.unseen_emitters().environment_unseen())
        report.say(std::string("note: the training view does not show ") +
                   (session.fit().scene->environment >= 0 ? "the environment" : "the void (no environment: black)") +
                   ": frames show it in its display colour where they look past every surface (docs/edits.md)");
    const fs::path out(job.out);
    fs::create_directories(out);
    std::ostringstream csv;
    csv << metrics_header(session.has_refiner()) << "\n";
    const auto start = std::chrono::steady_clock::now();
    const int frames = session.frames();
    const int first = job.first_frame, last = job.last_frame < 0 ? frames - 1 : job.last_frame;
    if (first < 0 || first > last || last >= frames)
        throw std::invalid_argument(job.edits + ": frames " + std::to_string(first) + ":" + std::to_string(last) +
                                    " are not within the sequence's 0:" + std::to_string(frames - 1));
    if (job.frame_step < 1) throw std::invalid_argument("frame step must be at least 1");
    const int count = (last - first) / job.frame_step + 1;
    const std::string key = frame_key(job, session, tools, files),
                      training_view_key = frame_hash(job, session, tools, files_without_edits);
    bool told = false;
    for (int i = first; i <= last; i += job.frame_step) {
        char name[64];
        std::snprintf(name, sizeof name, "frame_%04d.done", i);
        const fs::path done = out / name;
        std::optional<std::string> row;
        if (job.resume && fs::exists(done)) {
            row = finished_row(done, key);
            if (!row && !told) report.say(done.string() + " was made from another fit or settings: rendering again");
            told = told || !row;
        }
        if (!row) {
            row = frame_row(job, session, tools, i, w, h, out, training_view_key);
            write_text_atomic(done.string(), key + "\n" + *row);
        }
        if (job.reference) csv << *row << "\n";
        StageProgress p;
        p.stage = "edit";
        p.step = (i - first) / job.frame_step + 1;
        p.total = count;
        p.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (!report.step(p)) throw Cancelled("edit");
    }
    // A range given explicitly names its file even when it spans the sequence: a workflow's
    // chunk jobs then always write metrics_A-B.csv, whatever the chunking.
    const bool whole = job.first_frame == 0 && job.last_frame < 0;
    const std::string metrics =
        whole ? "metrics.csv" : "metrics_" + std::to_string(first) + "-" + std::to_string(last) + ".csv";
    if (job.reference) write_text_atomic((out / metrics).string(), csv.str());
    return count;
}

}  // namespace lpt::pipeline
