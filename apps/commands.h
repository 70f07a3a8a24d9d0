// Subcommand entry points. main.cpp owns all command-line parsing (one CLI11 translation unit);
// each subcommand file receives plain option structs.
#pragma once
#include "pipeline/fit.h"
#include "pipeline/paths.h"
#include "pipeline/progress.h"
#include "pipeline/reference.h"
#include "pipeline/refine.h"
#include "pipeline/resolution.h"
#include "pipeline/vae_source.h"
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lpt {
class Scene;
}

namespace lpt::app {

using pipeline::default_lpips_dir;
using pipeline::default_vae_dir;
using pipeline::parse_resolution;
using pipeline::shared_dir;
using pipeline::VaeSource;

struct RenderArgs {
    std::string scene;
    std::string out = "render.exr";
    int spp = 0;      ///< 0 = the scene's
    std::string res;  ///< "WxH", empty = the scene's
    uint64_t seed = 0;
    int max_depth = -2;  ///< -2 = the scene's
    std::string strategy = "mis";
    bool aov = false;
    std::string aov_res;  ///< "WxH", empty = the image's
    float exposure = 0.f;
    std::map<std::string, std::string> defines;
    std::optional<SamplerKind> sampler;  ///< --sampler: replaces the scene's (or the fit's)
    bool quiet = false;
    std::string edit;        ///< edits.json, when `scene` is a fit folder
    bool reference = false;  ///< also path trace + encode each edited frame, write metrics.csv
    int ref_spp = 256;
    uint64_t ref_seed = pipeline::kReferenceSeed;
    std::string reference_cache;  ///< folder keeping path-traced reference frames for reuse
    std::string frame_cache;      ///< with edit: folder keeping the training view's frames for reuse
    std::string frames;           ///< with edit: "A:B", only frames A..B (inclusive)
    bool resume = false;          ///< with edit: skip frames an earlier run finished
};
int run_render(const RenderArgs& args);
int run_render_edit(const RenderArgs& args);

struct BenchArgs {
    std::string scene;  ///< empty = the bundled Cornell box
    int spp = 16;
    int res = 256;
    int sphere_triangles = 100000;
    std::string out_json;   ///< optional machine-readable results
    bool fit = false;       ///< time fit iterations (forward / adjoint) instead of rays/s
    std::string fit_scene;  ///< default: ../shared/scenes/cbox/cbox_specular.xml, else ours
    int fit_res = 128;
    std::vector<int> fit_spp{16, 64, 256};
    std::string equal_error;             ///< fit folder: latent vs RGB time to equal error
    int max_spp = 1024;                  ///< --equal-error: highest RGB spp (latent: a quarter of it)
    bool equal_noise = false;            ///< spp and seconds to a noise target, Sobol vs independent
    std::string reference;               ///< --equal-noise: converged reference (default: Tungsten's, cornell box)
    int target_spp = 64;                 ///< --equal-noise: target = the independent sampler's noise at this spp
    int seeds = 2;                       ///< --equal-noise: renders per ladder point
    bool startup = false;                ///< process start-up times of light and heavy commands
    std::optional<SamplerKind> sampler;  ///< --sampler for --fit and --equal-error (the others run both)
};
int run_bench(const BenchArgs& args);
int run_bench_fit(const BenchArgs& args);
int run_bench_equal_error(const BenchArgs& args);
int run_bench_equal_noise(const BenchArgs& args);
int run_bench_startup(const BenchArgs& args);

/// `latentpt refine` and `latentpt fit`: the pipeline's jobs plus what only a terminal needs.
struct RefineArgs {
    pipeline::RefineJob job;
    bool quiet = false;
};
int run_refine(const RefineArgs& args);
/// "wrote ..." and the rendered / refined / VAE round-trip metrics of a finished stage 2.
/// `emitters`: the summary of `refine --emitters`, which wrote the emitter refiner's files.
void print_refine_summary(const std::string& fitdir, const pipeline::RefineSummary& summary, bool emitters = false);

struct FitArgs {
    pipeline::FitJob job;
    bool quiet = false;
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

struct MetricsArgs {
    std::string a, b, vae_dir;
    std::string pairs;  ///< file of tab-separated pairs ("-": stdin); JSON lines out
    bool json = false;
};
int run_metrics(const MetricsArgs&);

/// `latentpt compare`: bias of renders against an independent reference beyond their noise.
struct CompareArgs {
    std::vector<std::string> test, ref;  ///< >= 2 renders per side (independent seeds) estimate its noise
    std::string scene;                   ///< optional: masks directly seen emitters
    std::map<std::string, std::string> defines;
    int block = 32;
    double sigma = 3.0;             ///< a block beyond this many σ of its noise is flagged
    double mean_tolerance = 0.005;  ///< verdict: channel means within this relative difference
    double ratio_range = 0.1;       ///< ratio map saturates at 1 ± this
    float exposure = 0.f;
    std::string out_dir;
    bool strict = false;  ///< exit 3 when the verdict fails
};
int run_compare(const CompareArgs& a);

/// A pipeline reporter for the terminal: progress and notes on stderr (nothing when quiet, except
/// warnings).
pipeline::Reporter console_reporter(bool quiet);

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
