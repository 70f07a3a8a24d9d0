// Mean-reduced Huber and MSE losses and their gradients: docs/fitting.md (7)–(9).
// Means, not sums, so the loss scale (and hence Adam's effective step and the early-stopping
// min_delta) does not depend on the image resolution or channel count.
#include "autodiff/loss.h"

#include <cmath>
#include <stdexcept>

namespace lpt {

double huber_loss(const float* pred, const float* target, size_t n, float delta, float* d_pred) {
    if (n == 0) throw std::invalid_argument("huber_loss: empty buffers (mean of no elements)");
    if (!(delta > 0.0f) || !std::isfinite(delta))
        throw std::invalid_argument("huber_loss: delta must be finite and > 0");
    const double inv_n = 1.0 / double(n);
    const double d = delta;
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double r = double(pred[i]) - double(target[i]);
        const double a = std::fabs(r);
        // |r| == delta belongs to the quadratic side, as in PyTorch; both sides agree there in
        // value and slope, so the choice only matters for bit-exactness.
        if (a <= d) {
            sum += 0.5 * r * r;
            if (d_pred) d_pred[i] = float(r * inv_n);
        } else {
            sum += d * (a - 0.5 * d);
            // A NaN residual lands here (the comparison fails); keep it NaN in the gradient
            // so that Adam refuses the step instead of taking a ±delta one.
            const double slope = r > 0.0 ? d : (r < 0.0 ? -d : r);
            if (d_pred) d_pred[i] = float(slope * inv_n);
        }
    }
    return sum * inv_n;
}

double mse_loss(const float* pred, const float* target, size_t n, float* d_pred) {
    if (n == 0) throw std::invalid_argument("mse_loss: empty buffers (mean of no elements)");
    const double inv_n = 1.0 / double(n);
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double r = double(pred[i]) - double(target[i]);
        sum += r * r;
        if (d_pred) d_pred[i] = float(2.0 * r * inv_n);
    }
    return sum * inv_n;
}

bool check_finite(const float* values, size_t n, size_t* first_bad) {
    for (size_t i = 0; i < n; ++i) {
        if (!std::isfinite(values[i])) {
            if (first_bad) *first_bad = i;
            return false;
        }
    }
    return true;
}

}  // namespace lpt
