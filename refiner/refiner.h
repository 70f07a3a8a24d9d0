// The per-scene refiner (stage 2 of `latentpt fit`): a small CNN that maps the rendered latent
// plus AOVs (world shading normal, camera distance) at latent resolution to a residual that is
// added to the rendered latent. Torch-free interface: buffers are interleaved per pixel, row-major
// from the top-left, like films and vae.h. libtorch stays inside refiner/*.cpp. docs/refiner.md
// gives the architecture, the loss and the measured quality/time trade-offs.
#pragma once
#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace lpt {

class Vae;
class Lpips;

/// The refiner's body. conv: three convolutions at full resolution (3×3, 5×5, 3×3; the paper's
/// blocks, a 9×9 receptive field). unet: a two-level U-Net with skip connections (widths W/4,
/// W/2, W; a ~44-pixel receptive field), docs/refiner.md "U-Net".
enum class RefinerArch { Conv, UNet };

struct RefinerConfig {
    int latent_channels = 16;
    int expansion = 16;  ///< hidden width = expansion × latent_channels
    float squash = 3.f;  ///< inputs enter as tanh(x / squash); 3 = the TAESD decoder's soft clamp
    float dropout = 0.1f;
    float distance_scale = 1.f;  ///< distances are divided by this (the training view's mean hit distance)
    /// InstanceNorm after each convolution (ours). false: none, as the paper describes its network;
    /// then a pixel's output depends only on its 9×9 neighbourhood, not on the statistics of the
    /// crop or view around it (except within 4 pixels of an edge, where padding stands in).
    bool instance_norm = true;
    /// Inference window (latent pixels per side; 0 = the whole view at once). With InstanceNorm
    /// the output depends on the statistics of what the network sees, so a refiner trained on
    /// n×n crops is applied to n×n windows at stride n/2 whose outputs are averaged per pixel
    /// (docs/refiner.md "Windows"). A view no larger than the window is one window: the whole view.
    /// Files written before the option hold none and load as 0.
    int tile = 0;
    /// Latent pixels between neighbouring inference windows; 0 = tile / 2 (files written before
    /// the option hold none). Denser windows average the output over more crop statistics
    /// (docs/refiner.md "Windows"), at (tile / stride)² network passes per tile² pixels.
    int window_stride = 0;
    /// Files written before the option hold none and load as conv.
    RefinerArch arch = RefinerArch::Conv;
    /// Also read the three transport terms Ĩe, Ĩa, Ĩc of the same render (linear, before the tone
    /// curve; RefinerInput::terms) beside their toned sum: where light was occluded or came from
    /// the flat response, which the sum mixes (docs/refiner.md "Transport terms"). Files written
    /// before the option hold none and load as false.
    bool terms = false;
    /// Also read where emitters lie inside each pixel: emitter coverage of cells × cells sub-cells
    /// (RefinerInput::emitter; 0 = none). Files written before the option hold none and load as 0.
    int emitter_cells = 0;
};

/// Input channels the emitter cells add: one per sub-cell.
inline int emitter_cell_channels(const RefinerConfig& c) { return c.emitter_cells * c.emitter_cells; }

/// The stride refine() steps its windows by: window_stride, or half the window when that is 0.
inline int inference_stride(const RefinerConfig& c) {
    return c.window_stride > 0 ? c.window_stride : std::max(1, c.tile / 2);
}

inline const char* to_string(RefinerArch arch) { return arch == RefinerArch::UNet ? "unet" : "conv"; }
/// "conv" or "unet"; throws std::invalid_argument naming `option` otherwise. Inline: the
/// torch-free readers of the options (pipeline, apps) parse it without linking the network.
inline RefinerArch parse_refiner_arch(const std::string& name, const std::string& option) {
    if (name == "conv") return RefinerArch::Conv;
    if (name == "unet") return RefinerArch::UNet;
    throw std::invalid_argument(option + ": '" + name + "' is not a refiner architecture (conv or unet)");
}

/// What the refiner reads for one view: the rendered (tone-mapped) latent and its AOVs.
struct RefinerInput {
    int width = 0, height = 0;
    std::vector<float> latent;    ///< width × height × latent_channels
    std::vector<float> normal;    ///< width × height × 3
    std::vector<float> distance;  ///< width × height × 1 (0 where the camera ray escapes)
    /// width × height × 3·latent_channels: Ĩe, Ĩa, Ĩc of each pixel in turn (linear); read only by
    /// refiners with RefinerConfig::terms, empty otherwise.
    std::vector<float> terms;
    /// width × height × emitter_cells²: each sub-cell's emitter coverage (render_emitter_cells);
    /// read only by refiners with RefinerConfig::emitter_cells, empty otherwise.
    std::vector<float> emitter;
};

/// One training pair: a render of a view and what it should refine to.
struct RefinerExample {
    RefinerInput input;
    std::vector<float> target;      ///< width × height × latent_channels
    std::vector<float> target_rgb;  ///< 8 width × 8 height × 3 in [0, 1] for LPIPS; empty: the decoded target
};

struct RefinerTrainOptions {
    int iterations = 3000;
    float lr = 5e-4f;
    /// Off: every step at lr. On: lr falls along one half cosine from lr to 0 over `iterations`
    /// (SGDR's first period without restarts, as the fit's schedule with period = iterations).
    bool cosine_decay = false;
    /// loss = w·MSE + w·(1 − SSIM) + w·LPIPS. MSE alone by default: on cbox-specular's edits it
    /// beat our earlier mix (1, 1, 1) in both metrics at the same training time, because without
    /// a decoder in the loop a step costs a quarter (docs/refiner.md, docs/results.md).
    float w_mse = 1.f, w_ssim = 0.f, w_lpips = 0.f;
    int crop = 32;        ///< latent pixels per side of the training crop; 0 = the whole view
    int lpips_crop = 16;  ///< latent pixels per side decoded for LPIPS (8× in RGB); 0 = no LPIPS
    /// Standard deviation of Gaussian noise added to the rendered latent where the body reads it,
    /// not to the latent the body's output is added to; drawn afresh for every step from (seed,
    /// iteration). The body is trained to change its output little when its input changes a
    /// little, so it cannot tie its output to one render's noise (docs/refiner.md "Input noise").
    /// 0 = none: training as before the option. Refused with RefinerConfig::terms, whose terms
    /// carry the same render noise and would be read without it.
    float input_noise = 0.f;
    int patience = 500;  ///< early stopping on the smoothed loss; 0 = off
    float min_delta = 1e-5f;
    uint64_t seed = 0;
    int checkpoint_every = 100;   ///< 0 = only at the end
    std::string checkpoint_path;  ///< empty = no checkpoints
    bool resume = false;          ///< continue from checkpoint_path
};

struct RefinerRecord {
    int iteration = 0;
    double loss = 0, smoothed = 0, mse = 0, dssim = 0, lpips = 0, seconds = 0;
    /// The loss or a weight's gradient was not finite: the step was refused, weights and Adam
    /// state kept. refused_parameter names the weight ("loss" when the loss itself was bad).
    bool refused = false;
    std::string refused_parameter;
};

struct RefinerTrainResult {
    std::vector<RefinerRecord> history;  ///< every iteration since the start (resumed runs included)
    int best_iteration = -1;
    double best_loss = 0;
};

class Refiner {
public:
    /// A new network whose output convolution starts at zero, so it begins as the identity.
    static std::unique_ptr<Refiner> create(const RefinerConfig& config, uint64_t seed);
    /// Loads a file written by save(); throws std::runtime_error naming the file.
    static std::unique_ptr<Refiner> load(const std::string& path);
    ~Refiner();

    /// Writes weights and configuration atomically (temporary file + rename).
    void save(const std::string& path) const;
    /// Refined latent (width × height × latent_channels) of a view of any size; deterministic.
    std::vector<float> refine(const RefinerInput& input) const;

    /// Trains on one view against `target` (latent). LPIPS compares decoded crops with
    /// `target_rgb` (8w × 8h × 3 in [0, 1]) when given, else with the decoded target; it needs
    /// `vae` (differentiable) and `lpips`, and is skipped when either is null. `on_iteration`
    /// returning false stops early. Ends with the best (smoothed-loss) weights loaded.
    RefinerTrainResult train(const RefinerInput& input, const std::vector<float>& target,
                             const std::vector<float>* target_rgb, const Vae* vae, const Lpips* lpips,
                             const RefinerTrainOptions& options,
                             const std::function<bool(const RefinerRecord&)>& on_iteration = {});
    /// The same on several renders of the training view with independent samples (one camera, one
    /// target, different noise): each iteration's crop comes from one of them, chosen by (seed,
    /// iteration), so the network cannot learn one render's noise as if it were the scene. One
    /// view trains exactly as train() above.
    RefinerTrainResult train(const std::vector<RefinerInput>& noise_views, const std::vector<float>& target,
                             const std::vector<float>* target_rgb, const Vae* vae, const Lpips* lpips,
                             const RefinerTrainOptions& options,
                             const std::function<bool(const RefinerRecord&)>& on_iteration = {});
    /// The general form: each iteration's crop comes from one of the examples, drawn by (seed,
    /// iteration), and each example brings its own target (augmented views of the training view,
    /// docs/refiner.md "Augmentation"). Examples may differ in size; one example trains exactly
    /// as train() above.
    RefinerTrainResult train(const std::vector<RefinerExample>& examples, const Vae* vae, const Lpips* lpips,
                             const RefinerTrainOptions& options,
                             const std::function<bool(const RefinerRecord&)>& on_iteration = {});

    const RefinerConfig& config() const;
    /// Number of learnable weights (for reports).
    int64_t parameter_count() const;

    struct Impl;

private:
    explicit Refiner(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m;
};

}  // namespace lpt
