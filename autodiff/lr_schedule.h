// Learning-rate schedule and stopping rule of the fit loop: cosine annealing with warm restarts
// (SGDR, Loshchilov & Hutter 2017), docs/fitting.md (13)–(15), and early stopping on the loss,
// docs/fitting.md (16).
#pragma once
#include <cstdint>

namespace lpt {

/// PyTorch's CosineAnnealingWarmRestarts(T_0 = period, T_mult = t_mult, eta_min), with the
/// optimiser's lr as lr_max. lr_at(i) is the rate for the i-th optimiser step (0-based), i.e.
/// the lr PyTorch's scheduler holds after i calls of scheduler.step().
class CosineWarmRestarts {
public:
    /// Throws std::invalid_argument if period < 1, t_mult < 1 or a rate is not finite.
    explicit CosineWarmRestarts(float lr_max, int period = 500, int t_mult = 1, float eta_min = 0.0f);

    /// A pure function of the iteration, so a resumed fit continues on the same curve.
    /// lr_at(start of a cycle) = lr_max; halfway = (lr_max + eta_min) / 2.
    /// Throws std::invalid_argument for iteration < 0.
    float lr_at(int iteration) const;

    /// First iteration of the cycle containing `iteration`, and that cycle's length (T_i).
    void cycle_of(int iteration, int64_t* cycle_start, int64_t* cycle_length) const;

    float lr_max() const { return m_lr_max; }
    float eta_min() const { return m_eta_min; }
    int period() const { return m_period; }
    int t_mult() const { return m_t_mult; }

private:
    float m_lr_max;
    int m_period;
    int m_t_mult;
    float m_eta_min;
};

/// Stops the fit once `patience` consecutive updates brought no improvement, where an update
/// improves iff loss < best_loss − min_delta (docs/fitting.md (16)). A NaN loss never improves.
///
/// The parameters at the end of a fit are not the best ones: the caller must snapshot the
/// parameters (and whatever else it wants to return) whenever improved() is true after an
/// update, and restore that snapshot when update() says stop or the iteration budget ends.
class EarlyStopping {
public:
    /// Throws std::invalid_argument if patience < 1 or min_delta < 0 (or is not finite).
    EarlyStopping(int patience, float min_delta = 0.0f);

    /// Records the loss at `iteration`; true when the fit should stop (and from then on).
    bool update(double loss, int iteration);
    /// Whether the last update() set a new best (false before any update).
    bool improved() const { return m_improved; }
    /// Iteration of the best loss so far; −1 before the first improvement.
    int best_iteration() const { return m_best_iteration; }
    /// Best loss so far; +inf before the first improvement.
    double best_loss() const { return m_best_loss; }
    /// Consecutive non-improving updates since the last improvement.
    int bad_updates() const { return m_bad_updates; }
    /// Puts back the state a checkpoint recorded (resumed fits stop where uninterrupted ones do).
    void restore(double best_loss, int best_iteration, int bad_updates) {
        m_best_loss = best_loss;
        m_best_iteration = best_iteration;
        m_bad_updates = bad_updates;
        m_improved = false;
    }

private:
    int m_patience;
    double m_min_delta;
    double m_best_loss;
    int m_best_iteration = -1;
    int m_bad_updates = 0;
    bool m_improved = false;
};

}  // namespace lpt
