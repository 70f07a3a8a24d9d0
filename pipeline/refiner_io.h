// What the refiner reads beside a rendered latent: AOVs (normal, distance) of the same view, and
// their file in a fit folder (aov.exr, channels N.X N.Y N.Z Z).
#pragma once
#include "refiner/refiner.h"
#include <cstdint>
#include <string>
#include <vector>

namespace lpt {
class Scene;
}

namespace lpt::pipeline {
struct FitFolder;
}

namespace lpt::pipeline {

/// AOVs of `scene` at the latent's resolution, averaged over `spp` camera samples with `seed`
/// (as the latent was rendered), around `latent`.
RefinerInput refiner_view(const Scene& scene, std::vector<float> latent, int w, int h, int spp, uint64_t seed);
/// What a refiner with `config` reads of a fit's (possibly edited) scene rendered at w × h, spp
/// and seed: the toned latent (render_fit_latent's), its AOVs, and the transport terms when
/// config.terms (one render: the terms sum to the latent before its tone curve), and the emitter
/// cells when config.emitter_cells.
RefinerInput fit_refiner_view(const FitFolder& fit, const RefinerConfig& config, int w, int h, int spp, uint64_t seed);
void write_refiner_aovs(const std::string& path, const RefinerInput& in);
/// Throws naming the file when either is missing or has the wrong size or channels.
RefinerInput load_refiner_input(const std::string& latent_exr, const std::string& aov_exr);
/// Ĩe, Ĩa, Ĩc of a fit folder's final render (latent_e.exr, latent_a.exr, latent_c.exr) as
/// RefinerInput::terms; throws naming the file when one is missing or differs in size.
std::vector<float> load_refiner_terms(const std::string& fitdir, int w, int h);

}  // namespace lpt::pipeline
