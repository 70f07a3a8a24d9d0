// SSIM: the plain C++ ssim() of vae/ssim.h (double precision, separable Gaussian, 'valid'
// filtering) and the differentiable libtorch ssim_torch() of vae/lpips_torch.h, which computes
// the same thing with grouped 2-D convolutions (the pytorch-msssim formulation).
#include "vae/ssim.h"
#include "vae/lpips_torch.h"
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace lpt {

namespace {

/// Normalised 1-D Gaussian taps exp(-x^2 / (2 sigma^2)), x = -5..5 (scipy / pytorch-msssim).
std::vector<double> gaussian_taps() {
    std::vector<double> g(kSsimWindow);
    double sum = 0;
    for (int i = 0; i < kSsimWindow; ++i) {
        const double x = i - kSsimWindow / 2;
        g[i] = std::exp(-x * x / (2 * kSsimSigma * kSsimSigma));
        sum += g[i];
    }
    for (double& v : g) v /= sum;
    return g;
}

void check_args(int w, int h, int channels, double data_range, const char* who) {
    if (w < kSsimWindow || h < kSsimWindow)
        throw std::invalid_argument(std::string(who) + ": image " + std::to_string(w) + "x" + std::to_string(h) +
                                    " is smaller than the 11x11 window");
    if (channels < 1)
        throw std::invalid_argument(std::string(who) + ": channels must be >= 1, got " + std::to_string(channels));
    if (!(data_range > 0))
        throw std::invalid_argument(std::string(who) + ": data_range must be > 0, got " + std::to_string(data_range));
}

}  // namespace

double ssim(const float* a, const float* b, int w, int h, int channels, double data_range) {
    check_args(w, h, channels, data_range, "ssim");
    const std::vector<double> g = gaussian_taps();
    const double c1 = (0.01 * data_range) * (0.01 * data_range), c2 = (0.03 * data_range) * (0.03 * data_range);
    const int ow = w - kSsimWindow + 1, oh = h - kSsimWindow + 1;
    // Horizontal pass of the five moments (a, b, a^2, b^2, ab) into h x ow rows, then vertical.
    std::vector<double> rows(size_t(5) * h * ow);
    double total = 0;
    for (int c = 0; c < channels; ++c) {
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < ow; ++x) {
                double m[5] = {0, 0, 0, 0, 0};
                for (int k = 0; k < kSsimWindow; ++k) {
                    const size_t i = (size_t(y) * w + x + k) * channels + c;
                    const double va = a[i], vb = b[i], wk = g[k];
                    m[0] += wk * va;
                    m[1] += wk * vb;
                    m[2] += wk * (va * va);
                    m[3] += wk * (vb * vb);
                    m[4] += wk * (va * vb);  // a*b before the weight: symmetric in a, b
                }
                for (int q = 0; q < 5; ++q) rows[(size_t(q) * h + y) * ow + x] = m[q];
            }
        double sum = 0;
        for (int y = 0; y < oh; ++y)
            for (int x = 0; x < ow; ++x) {
                double m[5] = {0, 0, 0, 0, 0};
                for (int k = 0; k < kSsimWindow; ++k)
                    for (int q = 0; q < 5; ++q) m[q] += g[k] * rows[(size_t(q) * h + y + k) * ow + x];
                const double mu_a = m[0], mu_b = m[1];
                const double var_a = m[2] - mu_a * mu_a, var_b = m[3] - mu_b * mu_b, cov = m[4] - mu_a * mu_b;
                sum += ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) /
                       ((mu_a * mu_a + mu_b * mu_b + c1) * (var_a + var_b + c2));
            }
        total += sum / (double(ow) * oh);
    }
    return total / channels;
}

torch::Tensor ssim_torch(const torch::Tensor& a, const torch::Tensor& b, double data_range) {
    if (a.dim() != 4 || a.sizes() != b.sizes())
        throw std::invalid_argument("ssim_torch: expects two NCHW tensors of the same shape, got " +
                                    c10::str(a.sizes()) + " and " + c10::str(b.sizes()));
    const int64_t ch = a.size(1);
    check_args(int(a.size(3)), int(a.size(2)), int(ch), data_range, "ssim_torch");
    const std::vector<double> taps = gaussian_taps();
    torch::Tensor g = torch::tensor(taps, torch::TensorOptions().dtype(torch::kFloat64)).to(a.options());
    // Separable window as two grouped convolutions (one filter per channel), no padding.
    torch::Tensor gh = g.view({1, 1, 1, kSsimWindow}).expand({ch, 1, 1, kSsimWindow}).contiguous();
    torch::Tensor gv = g.view({1, 1, kSsimWindow, 1}).expand({ch, 1, kSsimWindow, 1}).contiguous();
    auto filt = [&](const torch::Tensor& x) {
        torch::Tensor y = torch::conv2d(x, gh, torch::Tensor(), /*stride=*/{1, 1}, /*padding=*/torch::IntArrayRef{0, 0},
                                        /*dilation=*/{1, 1}, /*groups=*/ch);
        return torch::conv2d(y, gv, torch::Tensor(), /*stride=*/{1, 1}, /*padding=*/torch::IntArrayRef{0, 0},
                             /*dilation=*/{1, 1}, /*groups=*/ch);
    };
    const double c1 = (0.01 * data_range) * (0.01 * data_range), c2 = (0.03 * data_range) * (0.03 * data_range);
    torch::Tensor mu_a = filt(a), mu_b = filt(b);
    torch::Tensor var_a = filt(a * a) - mu_a * mu_a;
    torch::Tensor var_b = filt(b * b) - mu_b * mu_b;
    torch::Tensor cov_ab = filt(a * b) - mu_a * mu_b;
    torch::Tensor map =
        ((2 * mu_a * mu_b + c1) * (2 * cov_ab + c2)) / ((mu_a * mu_a + mu_b * mu_b + c1) * (var_a + var_b + c2));
    return map.mean({2, 3}).mean(1);
}

}  // namespace lpt
