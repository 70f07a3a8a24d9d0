// Signed tone curves applied to the linear latent before the loss, with their derivatives.
// The latent is signed, so each curve acts on |x| and keeps the sign: T(x) = sign(x) c(|x|).
// Equations: docs/fitting.md (1)–(6).
#pragma once
#include <cstddef>
#include <string>

namespace lpt {

enum class ToneCurve {
    Clip,      ///< c(x) = 3 · clamp(x, 0, 3)^(1/2.2)          docs/fitting.md (2)
    Reinhard,  ///< c(x) = 4 · (x / (1 + x))^(1/2.2)           docs/fitting.md (4)
    None,      ///< identity
    /// The paper's baseline: a classic non-negative render x in [0, 1) mapped to latent space by
    /// logit(clamp(x, eps, 1 − eps)), eps = 1e-4 (not odd: the classic render is never
    /// negative). docs/fitting.md "Baseline".
    Logit,
};

/// Below this |x| the derivative is evaluated at |x| = eps: c'(x) ~ x^(1/2.2 − 1) is infinite
/// at 0. docs/fitting.md (6).
inline constexpr float k_tone_grad_eps = 1e-4f;

inline constexpr float k_logit_eps = 1e-4f;

/// "clip", "reinhard", "none" or "logit" (exact, lower case); std::invalid_argument otherwise.
ToneCurve parse_tone_curve(const std::string& name);
/// Inverse of parse_tone_curve.
const char* to_string(ToneCurve curve);

/// T(x), odd in x. docs/fitting.md (1).
float tone(ToneCurve curve, float x);
/// The x with T(x) = y, y first brought into T's range (clip: |x| ≤ 3; reinhard: |y| < 4; logit:
/// y's sigmoid within [eps, 1 − eps]): edits give a render a latent the VAE made.
float tone_inverse(ToneCurve curve, float y);
/// dT/dx, even in x, finite everywhere (0 where clip saturates, |x| > 3). docs/fitting.md (3), (5), (6).
float d_tone(ToneCurve curve, float x);

/// out[i] = T(in[i]) for i < n. `out` may alias `in`.
void tone_map(ToneCurve curve, const float* in, float* out, size_t n);
/// d_in[i] = d_out[i] · T'(in[i]): the chain rule through tone_map, given the primal input.
/// Overwrites d_in (does not accumulate); d_in may alias d_out.
void tone_map_backward(ToneCurve curve, const float* in, const float* d_out, float* d_in, size_t n);

}  // namespace lpt
