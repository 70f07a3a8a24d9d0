// SSIM (Wang, Bovik, Sheikh, Simoncelli 2004), plain C++, torch-free: interleaved float buffers
// (row-major from the top-left) with any channel count. The definition is the common one of
// pytorch-msssim `ssim(X, Y, data_range=L, win_size=11, win_sigma=1.5, K=(0.01, 0.03))` and of
// skimage `structural_similarity(a, b, data_range=L, channel_axis=-1, gaussian_weights=True,
// sigma=1.5, use_sample_covariance=False)`:
//   * normalised 11-tap Gaussian window, sigma 1.5, applied separably (11x11), 'valid' filtering
//     (no padding: (w-10) x (h-10) positions);
//   * mu = G*x, sigma_x^2 = G*(x^2) - mu_x^2, sigma_xy = G*(xy) - mu_x mu_y (population moments);
//   * SSIM map = (2 mu_a mu_b + C1)(2 sigma_ab + C2) / ((mu_a^2 + mu_b^2 + C1)(sigma_a^2 + sigma_b^2 + C2)),
//     C1 = (0.01 L)^2, C2 = (0.03 L)^2, L = data range;
//   * mean over positions per channel, then mean over channels.
// Data ranges used in latentpt (docs/metrics.md): images in [0, 1] -> L = 1; TAESD3 latents ->
// L = 6 (the decoder soft-clamps its input with 3 tanh(x/3), so the meaningful range is [-3, 3]).
// A differentiable libtorch version, ssim_torch, is declared in vae/lpips_torch.h.
#pragma once

namespace lpt {

constexpr int kSsimWindow = 11;
constexpr double kSsimSigma = 1.5;
constexpr double kImageDataRange = 1.0;
constexpr double kLatentDataRange = 6.0;

/// Mean SSIM of two w x h images with `channels` interleaved channels. 1 for identical images,
/// symmetric in a and b. Throws std::invalid_argument if w or h < 11, channels < 1, or
/// data_range <= 0.
double ssim(const float* a, const float* b, int w, int h, int channels, double data_range);

}  // namespace lpt
