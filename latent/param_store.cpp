#include "latent/param_store.h"
#include "core/sampler.h"
#include <nlohmann/json.hpp>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace lpt {

const char* to_string(ParamMap m) {
    switch (m) {
        case ParamMap::Identity:
            return "identity";
        case ParamMap::Sigmoid:
            return "sigmoid";
        case ParamMap::PosNeg:
            return "posneg";
        case ParamMap::Gain:
            return "gain";
    }
    return "?";
}

ParamMap param_map_from_string(const std::string& s) {
    if (s == "identity") return ParamMap::Identity;
    if (s == "sigmoid") return ParamMap::Sigmoid;
    if (s == "posneg") return ParamMap::PosNeg;
    if (s == "gain") return ParamMap::Gain;
    throw std::invalid_argument("unknown parameter map '" + s + "' (known: identity, sigmoid, posneg, gain)");
}

std::string ParamSlice::raw_problem(size_t k, float v) const {
    if (map != ParamMap::Gain || k != size_t(channels) || (v >= kGainLo && v <= kGainHi)) return "";
    return "log-gain " + std::to_string(v) + " outside [" + std::to_string(kGainLo) + ", " + std::to_string(kGainHi) +
           "]";
}

int ParamStore::add(const std::string& name, const std::string& kind, ParamMap map, int channels, float lo, float hi) {
    if (find(name) >= 0) throw std::invalid_argument("duplicate parameter '" + name + "'");
    if (channels <= 0 || !(lo <= hi))
        throw std::invalid_argument("parameter '" + name + "': bad channel count or range");
    if (map == ParamMap::Gain && !(lo <= 0.f && hi >= 0.f))  // a gain scales u; 0 must stay reachable
        throw std::invalid_argument("parameter '" + name + "': a gain slice's range must contain 0");
    ParamSlice s;
    s.name = name;
    s.kind = kind;
    s.map = map;
    s.channels = channels;
    s.lo = lo;
    s.hi = hi;
    s.raw_offset = m_raw.size();
    s.value_offset = m_value.size();
    m_raw.resize(m_raw.size() + s.raw_size(), 0.f);
    m_grad_raw.resize(m_raw.size(), 0.f);
    m_value.resize(m_value.size() + channels, 0.f);
    m_grad_value.resize(m_value.size(), 0.f);
    m_slices.push_back(s);
    update_values();
    return int(m_slices.size()) - 1;
}

int ParamStore::find(const std::string& name) const {
    for (size_t i = 0; i < m_slices.size(); ++i)
        if (m_slices[i].name == name) return int(i);
    return -1;
}

namespace {

/// docs/params.md (4): the smallest log-gain g >= 0 that brings every v / e^g inside [lo, hi].
void set_gain_value(const ParamSlice& s, const float* v, float* r) {
    float need = 1.f;
    for (int c = 0; c < s.channels; ++c) {
        if (!std::isfinite(v[c])) throw std::invalid_argument("parameter '" + s.name + "': value not finite");
        if (v[c] > 0.f && s.hi > 0.f) need = std::max(need, v[c] / s.hi);
        if (v[c] < 0.f && s.lo < 0.f) need = std::max(need, v[c] / s.lo);
        if ((v[c] > 0.f && s.hi <= 0.f) || (v[c] < 0.f && s.lo >= 0.f))
            throw std::invalid_argument("parameter '" + s.name + "': value outside its range");
    }
    const float g = std::log(need);
    // slack of a few ulp: 6·e^12, which clamp_raw produces, must come back
    if (g > kGainHi * (1.f + 1e-6f))
        throw std::invalid_argument("parameter '" + s.name + "': value beyond the largest gain");
    for (int c = 0; c < s.channels; ++c) r[c] = std::clamp(v[c] / need, s.lo, s.hi);
    r[s.channels] = std::min(g, kGainHi);
}

}  // namespace

void ParamStore::set_value(int i, const float* v) {
    const ParamSlice& s = m_slices[i];
    // Staged: a value refused at some channel leaves every raw parameter as it was.
    std::vector<float> staged(m_raw.begin() + s.raw_offset, m_raw.begin() + s.raw_offset + s.raw_size());
    float* r = staged.data();
    const auto commit = [&] {
        std::copy(staged.begin(), staged.end(), m_raw.begin() + s.raw_offset);
        update_values();
    };
    if (s.map == ParamMap::Gain) {
        set_gain_value(s, v, r);
        commit();
        return;
    }
    for (int c = 0; c < s.channels; ++c) {
        if (!std::isfinite(v[c])) throw std::invalid_argument("parameter '" + s.name + "': value not finite");
        switch (s.map) {
            case ParamMap::Identity:
                if (v[c] < s.lo || v[c] > s.hi)
                    throw std::invalid_argument("parameter '" + s.name + "': value outside its range");
                r[c] = v[c];
                break;
            case ParamMap::Sigmoid:
                if (!(v[c] > 0.f && v[c] < 1.f))
                    throw std::invalid_argument("parameter '" + s.name + "': sigmoid value must be in (0, 1)");
                r[c] = std::log(v[c] / (1.f - v[c]));
                break;
            case ParamMap::PosNeg: {
                float pos = std::max(v[c], 0.f), neg = std::max(-v[c], 0.f);
                if (pos + s.lo > s.hi || neg + s.lo > s.hi)
                    throw std::invalid_argument("parameter '" + s.name + "': value outside its range");
                r[c] = pos + s.lo;  // lo is normally 0; both parts start at lo
                r[c + s.channels] = neg + s.lo;
                break;
            }
            case ParamMap::Gain:
                break;  // handled above
        }
    }
    commit();
}

void ParamStore::update_values() {
    for (const ParamSlice& s : m_slices) {
        const float* r = m_raw.data() + s.raw_offset;
        float* v = m_value.data() + s.value_offset;
        // docs/params.md (4): one gain for the whole vector
        const float gain = s.map == ParamMap::Gain ? std::exp(r[s.channels]) : 1.f;
        for (int c = 0; c < s.channels; ++c) {
            switch (s.map) {
                case ParamMap::Identity:
                    v[c] = r[c];
                    break;
                case ParamMap::Sigmoid:
                    v[c] = 1.f / (1.f + std::exp(-r[c]));
                    break;
                // docs/params.md (3): the parts are kept inside [lo, hi] by clamp_raw, so the
                // difference is taken as is.
                case ParamMap::PosNeg:
                    v[c] = r[c] - r[c + s.channels];
                    break;
                case ParamMap::Gain:
                    v[c] = gain * r[c];
                    break;
            }
        }
    }
}

void ParamStore::backward() {
    for (const ParamSlice& s : m_slices) {
        const float* v = m_value.data() + s.value_offset;
        const float* gv = m_grad_value.data() + s.value_offset;
        float* gr = m_grad_raw.data() + s.raw_offset;
        const float gain = s.map == ParamMap::Gain ? std::exp(m_raw[s.raw_offset + s.channels]) : 1.f;
        if (s.map == ParamMap::Gain) gr[s.channels] = 0.f;
        for (int c = 0; c < s.channels; ++c) {
            switch (s.map) {
                case ParamMap::Identity:
                    gr[c] = gv[c];
                    break;
                case ParamMap::Sigmoid:
                    gr[c] = gv[c] * v[c] * (1.f - v[c]);
                    break;
                case ParamMap::PosNeg:
                    gr[c] = gv[c];
                    gr[c + s.channels] = -gv[c];
                    break;
                // docs/params.md (4): ∂v_c/∂u_c = e^g, ∂v_c/∂g = v_c
                case ParamMap::Gain:
                    gr[c] = gv[c] * gain;
                    gr[s.channels] += gv[c] * v[c];
                    break;
            }
        }
    }
}

void ParamStore::zero_grad() {
    std::fill(m_grad_value.begin(), m_grad_value.end(), 0.f);
    std::fill(m_grad_raw.begin(), m_grad_raw.end(), 0.f);
}

void ParamStore::clamp_raw() {
    for (const ParamSlice& s : m_slices) {
        if (s.map == ParamMap::Sigmoid) continue;  // unbounded raw by design
        float* r = m_raw.data() + s.raw_offset;
        for (size_t k = 0; k < s.vector_raw_size(); ++k) r[k] = std::clamp(r[k], s.lo, s.hi);
        if (s.map == ParamMap::Gain) r[s.channels] = std::clamp(r[s.channels], kGainLo, kGainHi);
    }
    update_values();
}

void ParamStore::init_uniform(const std::string& kind, float a, float b, uint64_t seed) {
    for (size_t i = 0; i < m_slices.size(); ++i) {
        const ParamSlice& s = m_slices[i];
        if (s.kind != kind) continue;
        for (size_t k = 0; k < s.vector_raw_size(); ++k)
            m_raw[s.raw_offset + k] = a + (b - a) * sample_1d(seed, uint32_t(i), uint32_t(k), 0);
        if (s.map == ParamMap::Gain) m_raw[s.raw_offset + s.channels] = 0.f;
    }
    clamp_raw();
}

std::string ParamStore::to_json() const {
    nlohmann::json j;
    j["slices"] = nlohmann::json::array();
    for (const ParamSlice& s : m_slices) {
        nlohmann::json e;
        e["name"] = s.name;
        e["kind"] = s.kind;
        e["map"] = to_string(s.map);
        e["lo"] = s.lo;
        e["hi"] = s.hi;
        e["raw"] = std::vector<float>(m_raw.begin() + s.raw_offset, m_raw.begin() + s.raw_offset + s.raw_size());
        e["value"] =
            std::vector<float>(m_value.begin() + s.value_offset, m_value.begin() + s.value_offset + s.channels);
        j["slices"].push_back(e);
    }
    return j.dump(1);
}

void ParamStore::load_json(const std::string& text, const std::string& file) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(file + ": malformed JSON: " + e.what());
    }
    if (!j.contains("slices") || !j["slices"].is_array())
        throw std::runtime_error(file + ": field 'slices' missing or not an array");
    for (const auto& e : j["slices"]) {
        if (!e.is_object() || !e.contains("name") || !e["name"].is_string())
            throw std::runtime_error(file + ": each of 'slices' must be an object with a string 'name'");
        const std::string name = e["name"].get<std::string>();
        int i = find(name);
        if (i < 0)
            throw std::runtime_error(file + ": unknown parameter '" + name +
                                     "' (no shape or kind of that name in this scene)");
        const ParamSlice& s = m_slices[i];
        if (!e.contains("raw") || !e["raw"].is_array() || e["raw"].size() != s.raw_size())
            throw std::runtime_error(file + ": parameter '" + name + "': 'raw' must hold " +
                                     std::to_string(s.raw_size()) + " numbers");
        if (e.contains("map") && e["map"] != to_string(s.map))
            throw std::runtime_error(file + ": parameter '" + name + "': map " + e["map"].dump() +
                                     " but this fit uses '" + to_string(s.map) + "'");
        for (size_t k = 0; k < s.raw_size(); ++k) {
            if (!e["raw"][k].is_number())
                throw std::runtime_error(file + ": parameter '" + name + "': raw[" + std::to_string(k) +
                                         "] is not a number");
            float v = e["raw"][k].get<float>();
            if (!std::isfinite(v))
                throw std::runtime_error(file + ": parameter '" + name + "': raw[" + std::to_string(k) +
                                         "] is not finite");
            const std::string problem = s.raw_problem(k, v);
            if (!problem.empty()) throw std::runtime_error(file + ": parameter '" + name + "': " + problem);
            m_raw[s.raw_offset + k] = v;
        }
    }
    update_values();
}

}  // namespace lpt
