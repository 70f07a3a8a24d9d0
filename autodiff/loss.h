// Image losses over flat float buffers (tone-mapped latents, any layout), mean-reduced, with
// their gradient d_pred = ∂loss/∂pred. Equations: docs/fitting.md (7)–(9).
#pragma once
#include <cstddef>

namespace lpt {

/// Huber loss, mean over the n elements: (1/n) Σ h_δ(pred − target), docs/fitting.md (7).
/// Matches torch.nn.HuberLoss(reduction="mean", delta). If d_pred is non-null it is overwritten
/// (not accumulated) with ∂loss/∂pred, docs/fitting.md (8). Sums in double.
/// Throws std::invalid_argument if n == 0 or delta <= 0 (or is not finite).
double huber_loss(const float* pred, const float* target, size_t n, float delta = 1.0f, float* d_pred = nullptr);

/// Mean squared error (1/n) Σ (pred − target)², docs/fitting.md (9); d_pred = 2 (pred − target) / n
/// when non-null (overwritten). Throws std::invalid_argument if n == 0.
double mse_loss(const float* pred, const float* target, size_t n, float* d_pred = nullptr);

/// True if all n values are finite. Otherwise false, and *first_bad (if non-null) receives the
/// index of the first NaN or ±inf, so the caller can say which pixel/channel went bad.
bool check_finite(const float* values, size_t n, size_t* first_bad = nullptr);

}  // namespace lpt
