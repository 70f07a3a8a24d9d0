// Ĩa and Ĩc, the latent renderer's terms beyond light transport, as a stage of the tracer of its
// own. The light-transport stages call it at the three points of a path where the terms are
// decided (an escape, a surface hit, the first vertex's light sample) and do not know what it
// adds; an RGB render has none. docs/transport.md (5)–(7).
#pragma once
#include "integrators/path.h"
#include "integrators/path_events.h"
#include "integrators/wavefront_state.h"
#include <stdexcept>
#include <string>

namespace lpt {

template <int N>
class LatentStage {
public:
    LatentStage(const LatentTerms<N>& terms, PathObserver<N>* observer) : m_terms(terms), m_obs(observer) {
        if (observer && !terms.looks.empty())
            throw std::invalid_argument("LatentTerms::looks in a render with an observer");
        check_look_indices(terms);
    }

    /// A camera ray met `shape` (-1: nothing; an emitter from its emitting side): with a look
    /// for it (LatentTerms::looks) it scores that into Ĩa and the path ends (true); else false.
    bool camera_look(PathState<N>& p, uint32_t slot, int shape) const {
        if (m_terms.looks.empty()) return false;
        const std::vector<int>& of_shape = m_terms.look_of_shape;  // empty: no shape has one
        const int i = shape < 0 ? m_terms.look_of_nothing : size_t(shape) < of_shape.size() ? of_shape[shape] : -1;
        return score_look(p, slot, i);
    }

    /// camera_look for a camera ray that meets the black back of a one-sided surface.
    bool camera_look_of_black(PathState<N>& p, uint32_t slot) const {
        return score_look(p, slot, m_terms.look_of_black);
    }

    /// A path escaped (or met a surface's black side, see hit()): the background joins Ĩa
    /// unless a non-delta vertex came before.
    void escaped(PathState<N>& p, uint32_t slot) const {
        if (!m_terms.ambient || p.past_first[slot]) return;
        p.ambient[slot] += ambient_score(p.beta[slot], m_terms.background);
        if (m_obs) m_obs->ambient(slot, -1);
    }

    /// A path reached a vertex of `shape`. At its first non-delta vertex: Ĩa, and true when that
    /// vertex's light sample is to decide Ĩc. `black_side`: the path met the back of a surface
    /// that scatters nothing from there (a one-sided BSDF), which RGB renders black like the
    /// void; before a first non-delta vertex the path then scores the background, as an escape
    /// does, rather than the surface's L̃a and L̃c, which describe its lit side.
    bool hit(PathState<N>& p, uint32_t slot, int shape, bool delta, bool black_side) const {
        if (p.past_first[slot]) return false;
        if (black_side) {
            escaped(p, slot);
            p.past_first[slot] = 1;
            return false;
        }
        if (delta) return false;
        p.past_first[slot] = 1;
        if (m_terms.ambient) {
            p.ambient[slot] += ambient_score(p.beta[slot], m_terms.La[shape]);
            if (m_obs) m_obs->ambient(slot, shape);
        }
        return m_terms.occlusion;
    }

    /// Ĩc's candidate at the first vertex of `shape`, held until its light sample's visibility is known.
    Spectrum<N> occlusion(const PathState<N>& p, uint32_t slot, int shape) const {
        return occlusion_score(p.beta[slot], m_terms.Lc[shape]);
    }

    /// The light sample's visibility is known: the candidate counts if it passes the gate.
    void gate(PathState<N>& p, uint32_t slot, const Spectrum<N>& candidate, bool visible) const {
        if (occlusion_gate_passes(m_terms.gate, visible)) p.occlusion[slot] += candidate;
    }

private:
    /// Every look index names a look or none (-1), checked once here rather than skipped per
    /// sample: a mismatch is a caller's error, and skipping it would render the fitted terms.
    static void check_look_indices(const LatentTerms<N>& terms) {
        auto check = [&](int i, const char* what) {
            if (i < -1 || (i >= 0 && size_t(i) >= terms.looks.size()))
                throw std::invalid_argument(std::string("LatentTerms::") + what + " names look " + std::to_string(i) +
                                            " of " + std::to_string(terms.looks.size()));
        };
        for (int i : terms.look_of_shape) check(i, "look_of_shape");
        check(terms.look_of_nothing, "look_of_nothing");
        check(terms.look_of_black, "look_of_black");
    }

    /// Scores looks[i] into Ĩa (true), or nothing where i < 0 (false).
    bool score_look(PathState<N>& p, uint32_t slot, int i) const {
        if (i < 0) return false;
        p.ambient[slot] += ambient_score(p.beta[slot], m_terms.looks[size_t(i)]);
        return true;
    }

    const LatentTerms<N>& m_terms;
    PathObserver<N>* m_obs;
};

}  // namespace lpt
