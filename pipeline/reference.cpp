#include "pipeline/reference.h"
#include "core/fingerprint.h"
#include "core/image_io.h"
#include "pipeline/fit_folder.h"
#include "core/sampler.h"
#include "core/scene.h"
#include "integrators/path.h"
#include "vae/vae.h"
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace lpt::pipeline {

float display_value(float v, const std::string& tone) {
    v = tone == "reinhard" ? std::abs(v) / (1.f + std::abs(v)) : std::clamp(v, 0.f, 1.f);
    return std::pow(v, 1.f / 2.2f);
}

bool float_image_path(const std::string& path) {
    const std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".hdr";
}

RgbValues rgb_values_of(const Image& img, const std::string& path) {
    if (!float_image_path(path)) return RgbValues::Display;
    return img.display ? RgbValues::MarkedDisplay : RgbValues::Linear;
}

std::vector<float> display_rgb(const Image& img, const std::string& path) {
    const RgbValues values = rgb_values_of(img, path);
    std::vector<float> rgb(size_t(img.width) * img.height * 3);
    for (size_t i = 0; i < size_t(img.width) * img.height; ++i)
        for (int c = 0; c < 3; ++c) {
            const float v = img.data[i * img.channels + c];
            rgb[i * 3 + c] = values == RgbValues::Linear          ? display_value(v, "clip")
                             : values == RgbValues::MarkedDisplay ? std::clamp(v, 0.f, 1.f)
                                                                  : v;
        }
    return rgb;
}

std::vector<float> linear_reference_of(const Scene& scene, int width, int height, int spp, uint64_t seed,
                                       const Reporter& report) {
    SceneSpectra<3> spectra = SceneSpectra<3>::from_description(scene);
    RenderOptions o = RenderOptions::from_scene(scene, width, height, spp, seed);
    RenderStats st;
    std::vector<float> rgb = render_path<3>(scene, spectra, o, &st).develop();
    std::ostringstream msg;
    msg << "reference: " << width << "x" << height << " at " << spp << " spp in " << st.seconds << " s";
    report.say(msg.str());
    return rgb;
}

std::vector<float> encoded_reference_of(const Scene& scene, int width, int height, int spp, uint64_t seed,
                                        const std::string& tone, const Vae& vae, const std::string& save_png,
                                        std::vector<float>* display_rgb, const Reporter& report,
                                        std::vector<float>* linear_rgb) {
    const int f = vae.convention().downsample;
    if (width % f || height % f)
        throw std::invalid_argument("reference resolution must be a multiple of " + std::to_string(f) +
                                    " in both axes, got " + std::to_string(width) + "x" + std::to_string(height));
    std::vector<float> rgb = linear_reference_of(scene, width, height, spp, seed, report);
    if (linear_rgb) *linear_rgb = rgb;
    for (float& v : rgb) v = display_value(v, tone);
    if (!save_png.empty()) write_png_display(save_png, Image{width, height, 3, rgb, {}});
    if (display_rgb) *display_rgb = rgb;
    return vae.encode(rgb, width, height);
}

namespace {

/// The linear RGB whose display mapping `display` (the cached `display_file`) is: `file` where it
/// holds this source's, else traced again (the same seed and sampler give the same pixels) and
/// written there where the folder lets us (a cache another user owns stays as it is). Caches
/// written before session 57 hold display values only. Throws, naming both files, where the
/// linear values do not map to the cached display values (traced by another build or sampler):
/// targets made from them would not be the training target's.
std::vector<float> cached_linear_reference(const Scene& scene, int width, int height, int spp, uint64_t seed,
                                           const std::string& tone, const std::string& file, const std::string& source,
                                           const std::vector<float>& display, const std::string& display_file,
                                           const Reporter& report) {
    std::vector<float> linear;
    if (std::filesystem::exists(file)) try {
            Image cached = read_fit_image(file, 3, width, height);
            if (cached.source == source && !cached.display) linear = std::move(cached.data);
        } catch (const std::exception&) {}  // unreadable or misshapen: traced again below
    if (linear.empty()) {
        report.say(file + ": tracing the reference's linear values again (the cache holds its display values only)");
        linear = linear_reference_of(scene, width, height, spp, seed, report);
        try {
            write_exr(file, Image{width, height, 3, linear, {"R", "G", "B"}, false, source});
        } catch (const std::exception&) {}
    }
    for (size_t i = 0; i < linear.size(); ++i)
        if (!(std::abs(display_value(linear[i], tone) - display[i]) <= 1e-6f))
            throw std::runtime_error(file + ": its linear values do not give the display values of " + display_file +
                                     " (value " + std::to_string(i) +
                                     "): traced by another build or sampler; delete both to trace the reference "
                                     "again");
    return linear;
}

/// "<W>x<H>_<spp>spp_<tone>": the part of every cache name that says how a reference was traced.
std::string trace_settings_key(int width, int height, int spp, const std::string& tone) {
    return std::to_string(width) + "x" + std::to_string(height) + "_" + std::to_string(spp) + "spp_" + tone;
}
}  // namespace

std::string training_reference_key(int width, int height, int spp, const std::string& tone) {
    return "training_" + trace_settings_key(width, height, spp, tone);
}

std::string edited_frame_reference_key(const std::string& edits_stem, int width, int height, int spp,
                                       const std::string& tone, const std::string& frame_name) {
    return edits_stem + "_" + trace_settings_key(width, height, spp, tone) + "_" + frame_name + kEditedFrameSeedTag;
}

uint64_t edited_frame_seed(uint64_t ref_seed, int frame) {
    return mix64(ref_seed ^ mix64(uint64_t(frame) + 1));  // frame + 1: frame 0 too differs from ref_seed
}

std::string reference_seed_suffix(uint64_t seed) {
    return seed == kReferenceSeed ? std::string() : "_seed" + std::to_string(seed);
}

std::string reference_source(const Scene& scene, const std::map<std::string, std::string>& defines,
                             const std::string& edits, int frame) {
    Fingerprint fingerprint;
    fingerprint.add(read_file(scene.file));
    for (const auto& [key, value] : defines) fingerprint.add(key + "=" + value);
    if (!edits.empty()) {
        fingerprint.add(read_file(edits));
        fingerprint.add("frame " + std::to_string(frame));
    }
    return "fnv1a64:" + fingerprint.hex();
}

std::vector<float> cached_encoded_reference(const Scene& scene, int width, int height, int spp, uint64_t seed,
                                            const std::string& tone, const Vae& vae, const std::string& cache_stem,
                                            const std::string& source, const std::string& encoder,
                                            const std::string& save_png, std::vector<float>& display_rgb,
                                            const Reporter& report, std::vector<float>* linear_rgb) {
    namespace fs = std::filesystem;
    if (cache_stem.empty())
        return encoded_reference_of(scene, width, height, spp, seed, tone, vae, save_png, &display_rgb, report,
                                    linear_rgb);
    const std::string rgb_file = cache_stem + ".exr", latent_file = cache_stem + "_latent.exr";
    const std::string linear_file = cache_stem + "_linear.exr";
    const int f = vae.convention().downsample, channels = vae.convention().channels;
    const std::string encoded_by = source + " encoded by " + encoder;
    const auto write_latent_file = [&](const std::vector<float>& latent) {
        write_exr(latent_file, Image{width / f, height / f, channels, latent, {}, false, encoded_by});
    };
    if (!fs::exists(rgb_file)) {
        std::vector<float> linear;
        std::vector<float> latent =
            encoded_reference_of(scene, width, height, spp, seed, tone, vae, save_png, &display_rgb, report, &linear);
        fs::create_directories(fs::path(cache_stem).parent_path());
        write_latent_file(latent);
        if (linear_rgb) {  // kept only where asked for (exposures): a full-size float image per frame
            write_exr(linear_file, Image{width, height, 3, linear, {"R", "G", "B"}, false, source});
            *linear_rgb = std::move(linear);
        }
        write_exr(rgb_file, Image{width, height, 3, display_rgb, {"R", "G", "B"}, true, source});
        return latent;
    }
    Image cached = read_fit_image(rgb_file, 3, width, height);
    if (!cached.source.empty() && cached.source != source)
        throw std::runtime_error(rgb_file + ": a cached reference of another scene, -D defines or edit sequence (" +
                                 cached.source + ", this one " + source + " of " + scene.file +
                                 "): give each scene its own cache folder, or delete the file to trace it again");
    if (!cached.display || cached.source.empty()) {
        // Written before EXRs carried the display mark (43b57c8): the same display values, unmarked,
        // which `metrics` would read as linear and map twice; or before they recorded their source
        // (taken to be this one's, as it was then). Marked in place, pixels unchanged; a cache this
        // process may only read (another user's folder) stays as it is.
        cached.display = true;
        cached.source = source;
        try {
            write_exr(rgb_file, cached);
        } catch (const std::exception&) {}
    }
    display_rgb = std::move(cached.data);
    if (linear_rgb)
        *linear_rgb = cached_linear_reference(scene, width, height, spp, seed, tone, linear_file, source, display_rgb,
                                              rgb_file, report);
    if (!save_png.empty()) write_png_display(save_png, Image{width, height, 3, display_rgb, {}});
    if (fs::exists(latent_file)) {
        Image latent = read_fit_image(latent_file, channels, width / f, height / f);
        if (latent.source == encoded_by) return latent.data;
        if (latent.source.empty()) {  // from before latents recorded their encoder: taken as this one's
            latent.source = encoded_by;
            try {
                write_exr(latent_file, latent);
            } catch (const std::exception&) {}
            return latent.data;
        }
        // another VAE's encoding of the same picture (a run with another --vae-*): encoded again
        report.say(latent_file + " was encoded by another VAE: encoding it again");
    }
    std::vector<float> latent = vae.encode(display_rgb, width, height);
    write_latent_file(latent);
    return latent;
}

}  // namespace lpt::pipeline
