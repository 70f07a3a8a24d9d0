// The base of the BSDFs built on one MicrofacetDistribution (roughconductor, roughdielectric,
// roughplastic): it owns the distribution and exposes its roughness as the scalar key "alpha"
// to fitting, so the three share one definition of that key.
#pragma once
#include "core/bsdf.h"
#include "core/bsdfs/microfacet.h"

namespace lpt {

template <int N>
class MicrofacetBSDF : public BSDF<N> {
public:
    explicit MicrofacetBSDF(const Props& props) : m_distr(read_distribution(props), read_alpha(props)) {}

    std::vector<std::string> scalar_keys() const override { return {"alpha"}; }
    float get_scalar(const std::string& key) const override {
        if (key != "alpha") return BSDF<N>::get_scalar(key);
        return m_distr.alpha();
    }
    /// Raised to MicrofacetDistribution::kMinAlpha (1e-4) as at construction; then alpha_changed()
    /// runs, unless the clamped value is the one already held. Non-finite values throw
    /// std::invalid_argument; other keys go to the base class, which throws.
    void set_scalar(const std::string& key, float value) override {
        if (key != "alpha") BSDF<N>::set_scalar(key, value);
        float old = m_distr.alpha();
        m_distr.set_alpha(value);
        if (m_distr.alpha() != old) alpha_changed();
    }

protected:
    /// Rebuilds whatever a subclass derives from alpha (roughplastic's tables); nothing by default.
    virtual void alpha_changed() {}

    MicrofacetDistribution m_distr;
};

}  // namespace lpt
