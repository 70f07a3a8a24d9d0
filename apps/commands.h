// Subcommand entry points. main.cpp owns all command-line parsing (one CLI11 translation unit);
// each subcommand file receives plain option structs.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace lpt {
class Scene;
class Vae;
struct RefinerInput;
}

namespace lpt::app {

/// Which autoencoder: TAESD3 weights in `dir` (native), or a TorchScript export (all three of
/// encoder, decoder, config; tools/export_vae.py makes them for the SD3.5 VAE).
struct VaeSource {
    std::string dir;                       ///< empty = ../shared/models/taesd3 (LATENTPT_SHARED overrides)
    std::string encoder, decoder, config;  ///< TorchScript modules and vae.json
    bool torchscript() const { return !encoder.empty() || !decoder.empty() || !config.empty(); }
};
/// Loads the VAE; throws with the file name if it is missing or broken, or if only part of the
/// TorchScript triple is given.
std::unique_ptr<lpt::Vae> open_vae(const VaeSource& source);
/// Whether open_vae can be expected to find its files (for "no VAE: latents only" fallbacks).
bool vae_present(const VaeSource& source);
/// The VAE a fit folder used (fit.json), with the defaults resolved.
VaeSource manifest_vae(const std::string& fit_json_path);

struct RenderArgs {
    std::string scene;
    std::string out = "render.exr";
    int spp = 0;                  ///< 0 = the scene's
    std::string res;              ///< "WxH", empty = the scene's
    uint64_t seed = 0;
    int max_depth = -2;           ///< -2 = the scene's
    std::string strategy = "mis";
    bool aov = false;
    std::string aov_res;          ///< "WxH", empty = the image's
    float exposure = 0.f;
    std::map<std::string, std::string> defines;
    bool quiet = false;
    std::string edit;             ///< edits.json, when `scene` is a fit folder
    bool reference = false;       ///< also path trace + encode each edited frame, write metrics.csv
    int ref_spp = 256;
    std::string reference_cache;  ///< folder keeping path-traced reference frames for reuse
};
int run_render(const RenderArgs& args);
int run_render_edit(const RenderArgs& args);

struct BenchArgs {
    std::string scene;            ///< empty = the bundled Cornell box
    int spp = 16;
    int res = 256;
    int sphere_triangles = 100000;
    std::string out_json;         ///< optional machine-readable results
    bool fit = false;             ///< time fit iterations (forward / adjoint) instead of rays/s
    std::string fit_scene;        ///< default: ../shared/scenes/cbox/cbox_specular.xml, else ours
    int fit_res = 128;
    std::vector<int> fit_spp{16, 64, 256};
    std::string equal_error;      ///< fit folder: latent vs RGB time to equal error
    int max_spp = 1024;           ///< --equal-error: highest RGB spp (latent: a quarter of it)
    bool equal_noise = false;     ///< spp and seconds to a noise target, Sobol vs independent
    std::string reference;        ///< --equal-noise: converged reference (default: Tungsten's, cornell box)
    int target_spp = 64;          ///< --equal-noise: target = the independent sampler's noise at this spp
    int seeds = 2;                ///< --equal-noise: renders per ladder point
};
int run_bench(const BenchArgs& args);
int run_bench_fit(const BenchArgs& args);
int run_bench_equal_error(const BenchArgs& args);
int run_bench_equal_noise(const BenchArgs& args);

/// Stage 2 on a fit folder: trains the refiner on the folder's final render (latent.exr, aov.exr)
/// against target.exr (and reference_rgb.exr for LPIPS when present).
struct RefineArgs {
    std::string fitdir;
    int iterations = 3000, expansion = 16, crop = 32, lpips_crop = 16, patience = 500, checkpoint_every = 100;
    float lr = 5e-4f, w_mse = 1.f, w_ssim = 1.f, w_lpips = 1.f, squash = 3.f, dropout = 0.1f;
    uint64_t seed = 0;
    bool resume = false, quiet = false;
    std::string lpips_dir;  ///< default: ../shared/models/lpips
};
int run_refine(const RefineArgs& args);
/// The refiner's view of a rendered latent: AOVs (normal, distance) of `scene` at the latent's
/// resolution, averaged over `spp` camera samples with `seed` (as the latent was rendered).
RefinerInput refiner_view(const lpt::Scene& scene, std::vector<float> latent, int w, int h, int spp, uint64_t seed);
/// aov.exr of a fit folder (channels N.X N.Y N.Z Z) and its reader (with latent.exr).
void write_refiner_aovs(const std::string& path, const RefinerInput& in);
RefinerInput load_refiner_input(const std::string& latent_exr, const std::string& aov_exr);

struct FitArgs {
    std::string scene, target, out = "fit-out";
    std::string synthetic_res = "32x32";  ///< used when no --target is given
    uint64_t synthetic_seed = 1;
    int iterations = 3000, spp = 16, final_spp = 256;
    uint64_t seed = 0;
    float lr = 1e-3f, lr_min = 0.f, min_delta = 1e-5f;
    int lr_period = 500, patience = 300, checkpoint_every = 100, reuse_paths = 8;
    std::string tone = "clip", param = "code", gate = "shadowed", terms = "eac";
    bool resume = false, quiet = false;
    std::map<std::string, std::string> defines;
    bool encode = false;          ///< target = VAE encoding of an RGB path trace of the scene
    std::string encode_res = "256x256";  ///< image resolution for --encode (latent = image / 8)
    int ref_spp = 256;
    std::string ref_tone = "clip";       ///< clip to [0, 1] or reinhard |x|/(1+|x|), then gamma 1/2.2
    VaeSource vae;
    bool refiner = true;                 ///< run stage 2 after stage 1
    RefineArgs refine;                   ///< stage-2 options (fitdir, seed, resume, quiet are filled in)
};
int run_fit(const FitArgs& args);

struct VaeArgs {
    std::string input, out;
    VaeSource vae;
    bool quiet = false;
};
int run_encode(const VaeArgs& args);
int run_decode(const VaeArgs& args);
int run_viz(const VaeArgs& args);

struct MetricsArgs { std::string a, b, vae_dir; bool json = false; };
int run_metrics(const MetricsArgs&);

/// `latentpt compare`: bias of renders against an independent reference beyond their noise.
struct CompareArgs {
    std::vector<std::string> test, ref;  ///< >= 2 renders per side (independent seeds) estimate its noise
    std::string scene;                   ///< optional: masks directly seen emitters
    std::map<std::string, std::string> defines;
    int block = 32;
    double sigma = 3.0;                  ///< a block beyond this many σ of its noise is flagged
    double mean_tolerance = 0.005;       ///< verdict: channel means within this relative difference
    double ratio_range = 0.1;            ///< ratio map saturates at 1 ± this
    float exposure = 0.f;
    std::string out_dir;
    bool strict = false;                 ///< exit 3 when the verdict fails
};
int run_compare(const CompareArgs& a);

/// The shared data folder: LATENTPT_SHARED, else ../shared beside the source tree.
std::string shared_dir();
/// ../shared (LATENTPT_SHARED overrides) + "/models/taesd3" unless `dir` is given.
std::string default_vae_dir(const std::string& dir);
/// ../shared (LATENTPT_SHARED overrides) + "/models/lpips" unless `dir` is given.
std::string default_lpips_dir(const std::string& dir);
/// The paper's display mapping for references: clip to [0, 1] (or |x|/(1+|x|) for "reinhard"),
/// then x^(1/2.2).
float display_value(float v, const std::string& tone);
/// Path-traced RGB of `scene` at width x height, tone-mapped as the paper does for its
/// references (clip or reinhard, then gamma 1/2.2), encoded by `vae`. `display_rgb`, if given,
/// receives the tone-mapped RGB that was encoded.
std::vector<float> encoded_reference_of(const lpt::Scene& scene, int width, int height, int spp, const std::string& tone,
                                        const lpt::Vae& vae, bool quiet, const std::string& save_png,
                                        std::vector<float>* display_rgb = nullptr);

/// Parses "WxH"; throws std::invalid_argument with a clear message.
void parse_resolution(const std::string& s, int& w, int& h);

/// Prints "\r[label] 45.0% | 12.3 Mrays/s | ETA 3.2 s" to stderr, at most every 0.25 s.
class Progress {
public:
    explicit Progress(std::string label, bool enabled = true);
    void update(double fraction, uint64_t rays);
    void finish(uint64_t rays);

private:
    std::string m_label;
    bool m_enabled;
    double m_start, m_last = -1.0;
};

}  // namespace lpt::app
