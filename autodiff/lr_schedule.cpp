// SGDR learning rate, docs/fitting.md (13)–(15), and the early-stopping rule, (16).
//
// The cycle is located with integer arithmetic. PyTorch's closed form
// n = floor(log_{T_mult}(i / T_0 · (T_mult − 1) + 1)) goes through a floating-point log, which can
// land just below an integer at the exact start of a cycle and place that step at the end of the
// previous one (lr ≈ eta_min instead of lr_max). Elsewhere both give the same cycle.
#include "autodiff/lr_schedule.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace lpt {

CosineWarmRestarts::CosineWarmRestarts(float lr_max, int period, int t_mult, float eta_min)
    : m_lr_max(lr_max), m_period(period), m_t_mult(t_mult), m_eta_min(eta_min) {
    if (period < 1) throw std::invalid_argument("SGDR: period must be >= 1, got " + std::to_string(period));
    if (t_mult < 1) throw std::invalid_argument("SGDR: t_mult must be >= 1, got " + std::to_string(t_mult));
    if (!std::isfinite(lr_max) || !std::isfinite(eta_min))
        throw std::invalid_argument("SGDR: lr_max and eta_min must be finite");
}

void CosineWarmRestarts::cycle_of(int iteration, int64_t* cycle_start, int64_t* cycle_length) const {
    if (iteration < 0) throw std::invalid_argument("SGDR: negative iteration " + std::to_string(iteration));
    int64_t start = 0, length = m_period;
    if (m_t_mult == 1) {
        start = int64_t(iteration) / length * length;
    } else {
        // Cycle lengths grow geometrically, so this runs at most ~31 times for an int iteration.
        while (iteration >= start + length) {
            start += length;
            length *= m_t_mult;
        }
    }
    *cycle_start = start;
    *cycle_length = length;
}

float CosineWarmRestarts::lr_at(int iteration) const {
    int64_t start, length;
    cycle_of(iteration, &start, &length);
    const double t_cur = double(iteration - start);
    const double pi = 3.14159265358979323846;
    // docs/fitting.md (15)
    return float(double(m_eta_min) +
                 (double(m_lr_max) - double(m_eta_min)) * 0.5 * (1.0 + std::cos(pi * t_cur / double(length))));
}

EarlyStopping::EarlyStopping(int patience, float min_delta)
    : m_patience(patience), m_min_delta(min_delta), m_best_loss(std::numeric_limits<double>::infinity()) {
    if (patience < 1) throw std::invalid_argument("early stopping: patience must be >= 1");
    if (!(min_delta >= 0.0f) || !std::isfinite(min_delta))
        throw std::invalid_argument("early stopping: min_delta must be finite and >= 0");
}

bool EarlyStopping::update(double loss, int iteration) {
    // docs/fitting.md (16). Written as a positive comparison so NaN counts as no improvement;
    // the first finite loss always improves on the initial +inf.
    m_improved = loss < m_best_loss - m_min_delta;
    if (m_improved) {
        m_best_loss = loss;
        m_best_iteration = iteration;
        m_bad_updates = 0;
    } else {
        ++m_bad_updates;
    }
    return m_bad_updates >= m_patience;
}

}  // namespace lpt
