// Signed tone curves T(x) = sign(x) c(|x|) and their derivatives: docs/fitting.md (1)–(6).
//
// The clip curve follows its spec literally: y = clip(x, 0, 3); y = y^(1/2.2); y = 3 y. It is
// therefore not normalised: c(1) = 3 and c(3) = 3 · 3^(1/2.2) ≈ 4.943 (not 3).
//
// Safe gradient at 0: c'(x) ∝ x^(1/2.2 − 1) = x^(−0.545) diverges as x → 0. The paper's PyTorch
// code gets it from autograd of pow, which is +inf at exactly 0 and, once multiplied by the 0
// gradient of an unselected torch.where branch or a saturated clamp, NaN. We instead evaluate
// the derivative at max(|x|, eps), eps = 1e-4: it is then continuous, bounded (clip: ≈ 207,
// reinhard: ≈ 276 at |x| ≤ eps) and exact for |x| ≥ eps; only latents within 1e-4 of 0 get the
// surrogate slope. Its sign is still right (T is increasing), so descent is not misled there.
#include "autodiff/tone_curve.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lpt {
namespace {

constexpr float k_gamma = 1.0f / 2.2f;
constexpr float k_clip_max = 3.0f;
constexpr float k_clip_scale = 3.0f;
constexpr float k_reinhard_scale = 4.0f;

// c(a) for a >= 0.
float curve(ToneCurve kind, float a) {
    switch (kind) {
        case ToneCurve::Clip:
            return k_clip_scale * std::pow(std::min(a, k_clip_max), k_gamma);
        case ToneCurve::Reinhard:
            return k_reinhard_scale * std::pow(a / (1.0f + a), k_gamma);
        case ToneCurve::None:
        case ToneCurve::Logit:  // handled in tone()
            return a;
    }
    return a;
}

// c'(a) for a >= 0, with the eps guard of docs/fitting.md (6).
float d_curve(ToneCurve kind, float a) {
    switch (kind) {
        case ToneCurve::Clip: {
            // Strictly above the clip the slope is 0. At exactly 3 we keep the left slope, as
            // torch.clamp's backward does (its pass-through mask is min <= x <= max).
            if (a > k_clip_max) return 0.0f;
            const float a_eff = std::max(a, k_tone_grad_eps);
            return k_clip_scale * k_gamma * std::pow(a_eff, k_gamma - 1.0f);
        }
        case ToneCurve::Reinhard: {
            const float a_eff = std::max(a, k_tone_grad_eps);
            const float inv = 1.0f / (1.0f + a_eff);
            const float y = a_eff * inv;
            return k_reinhard_scale * k_gamma * std::pow(y, k_gamma - 1.0f) * inv * inv;
        }
        case ToneCurve::None:
        case ToneCurve::Logit:  // handled in d_tone()
            return 1.0f;
    }
    return 1.0f;
}

}  // namespace

ToneCurve parse_tone_curve(const std::string& name) {
    if (name == "clip") return ToneCurve::Clip;
    if (name == "reinhard") return ToneCurve::Reinhard;
    if (name == "none") return ToneCurve::None;
    if (name == "logit") return ToneCurve::Logit;
    throw std::invalid_argument("unknown tone curve '" + name + "' (expected clip, reinhard, none or logit)");
}

const char* to_string(ToneCurve curve) {
    switch (curve) {
        case ToneCurve::Clip:
            return "clip";
        case ToneCurve::Reinhard:
            return "reinhard";
        case ToneCurve::None:
            return "none";
        case ToneCurve::Logit:
            return "logit";
    }
    return "none";
}

float tone(ToneCurve kind, float x) {
    if (kind == ToneCurve::Logit) {
        const float y = std::clamp(x, k_logit_eps, 1.0f - k_logit_eps);
        return std::log(y / (1.0f - y));
    }
    // Odd extension, docs/fitting.md (1): the negative half mirrors the positive one so that
    // the sign of the latent survives tone mapping.
    return x < 0.0f ? -curve(kind, -x) : curve(kind, x);
}

float tone_inverse(ToneCurve kind, float y) {
    if (kind == ToneCurve::Logit) return std::clamp(1.0f / (1.0f + std::exp(-y)), k_logit_eps, 1.0f - k_logit_eps);
    const float b = std::abs(y);
    float a = b;
    if (kind == ToneCurve::Clip) {
        a = std::pow(b / k_clip_scale, 1.0f / k_gamma);
        a = std::min(a, k_clip_max);
    } else if (kind == ToneCurve::Reinhard) {
        // c(a) = 4 u^γ with u = a / (1 + a) < 1: a = u / (1 − u)
        const float u = std::min(std::pow(b / k_reinhard_scale, 1.0f / k_gamma), 1.0f - 1e-6f);
        a = u / (1.0f - u);
    }
    return y < 0.0f ? -a : a;
}

float d_tone(ToneCurve kind, float x) {
    // Logit: 1 / (x (1 − x)) inside [eps, 1 − eps], 0 where the clamp holds (the true
    // derivative). A surrogate slope there (the clamp's, ~1e4) let the few pixels that see a
    // light directly (x > 1) pin the light's radiance: measured, the fit then stalls at Huber
    // 3.6 on the Cornell box.
    if (kind == ToneCurve::Logit) {
        if (x < k_logit_eps || x > 1.0f - k_logit_eps) return 0.0f;
        return 1.0f / (x * (1.0f - x));
    }
    // d/dx [−c(−x)] = c'(−x): the derivative of an odd function is even.
    return d_curve(kind, std::fabs(x));
}

void tone_map(ToneCurve kind, const float* in, float* out, size_t n) {
    for (size_t i = 0; i < n; ++i) out[i] = tone(kind, in[i]);
}

void tone_map_backward(ToneCurve kind, const float* in, const float* d_out, float* d_in, size_t n) {
    for (size_t i = 0; i < n; ++i) d_in[i] = d_out[i] * d_tone(kind, in[i]);
}

}  // namespace lpt
