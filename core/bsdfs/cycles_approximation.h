// The validation-only key "cycles_approximation" (bool, default false) of plastic, roughplastic
// and roughconductor: render the plugin as tools/cycles_reference.py's Blender translation
// approximates it, so that a difference between latentpt and Cycles can be split into what the
// translation changes and what is left (docs/validation.md, "Splitting a difference";
// docs/bsdfs.md (47)-(49)). Blender 3.4's shader nodes see only the view direction, never the
// light's, so the translation replaces each factor of the light direction θo by its
// cosine-weighted mean, takes the rough conductor's Fresnel at the macro normal, and gives
// roughplastic's Fresnel-free specular lobe Mitsuba's albedo per view angle. With this key our
// renders make the same replacements and nothing else.
// RGB only: the latent renderer and the fit refuse it (they would fit a different model).
#pragma once
#include "core/props.h"

namespace lpt {

template <int N>
bool read_cycles_approximation(const Props& props) {
    const bool on = props.get_bool("cycles_approximation", false);
    if (on && N != 3)
        props.fail("cycles_approximation",
                   "validation only (RGB renders, docs/validation.md); not allowed in latent renders or fits");
    return on;
}

}  // namespace lpt
