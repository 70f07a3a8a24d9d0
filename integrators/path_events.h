// What each scoring event of a path adds, written once. The wavefront tracer adds these to its
// films as it goes (integrators/path_tracer.cpp, latent_stage.h), and the path-replay sweeps
// (autodiff/path_record.cpp) evaluate the same formulas on recorded paths with the current
// coefficients: forward with the recorded throughput β, backward with β = 1 for the radiance R
// that flows into earlier bounces. docs/transport.md (2)–(7), docs/path-replay.md (1)–(3).
#pragma once
#include "core/spectrum.h"

namespace lpt {

/// Ĩc's gate at the first non-delta vertex: add L̃c where the light sample is blocked (the
/// paper's prose and public code; default) or where it is visible (the paper's equation, V).
enum class OcclusionGate { Shadowed, Visible };

/// Ĩe, an emitter reached by BSDF sampling or by escaping: β · (w_mis · L̃e). (3)
template <int N>
Spectrum<N> emission_score(const Spectrum<N>& beta, float mis, const Spectrum<N>& le) {
    return beta * (mis * le);
}

/// Ĩe by next-event estimation, where the shadow ray is unblocked: β · f · L̃e · (w_mis / p). (2)
template <int N>
Spectrum<N> nee_score(const Spectrum<N>& beta, const Spectrum<N>& f, const Spectrum<N>& le, float w_over_pdf) {
    return beta * f * le * w_over_pdf;
}

/// Ĩa: β · L̃a at the first non-delta vertex, or β · background for a path that escapes, or
/// meets the back of a one-sided surface, before reaching one (along delta bounces). (6)
template <int N>
Spectrum<N> ambient_score(const Spectrum<N>& beta, const Spectrum<N>& la) {
    return beta * la;
}

/// Ĩc: β · L̃c at the first non-delta vertex, where that vertex's light sample passes the gate. (7)
template <int N>
Spectrum<N> occlusion_score(const Spectrum<N>& beta, const Spectrum<N>& lc) {
    return beta * lc;
}

/// Whether Ĩc counts for a light sample whose shadow ray is (not) blocked. A light sample that
/// needs no ray (attached shadow, no light) is not visible.
inline bool occlusion_gate_passes(OcclusionGate gate, bool visible) {
    return visible != (gate == OcclusionGate::Shadowed);
}

}  // namespace lpt
