// `latentpt refine <fitdir>`: stage 2 on a finished fit, run by pipeline::run_refine, and a
// summary of metrics.json on the terminal.
#include "apps/commands.h"
#include "pipeline/refine.h"
#include <cstdio>

namespace lpt::app {

namespace {

void show(const nlohmann::json& m, const char* key) {
    if (!m.contains(key)) return;
    const auto& j = m[key];
    std::fprintf(stderr, "  %-14s", key);
    if (j.contains("latent_mse")) std::fprintf(stderr, " latent MSE %.5f", j["latent_mse"].get<double>());
    if (j.contains("rgb_mse_x100")) std::fprintf(stderr, " | RGB MSE×100 %.4f", j["rgb_mse_x100"].get<double>());
    if (j.contains("rgb_lpips")) std::fprintf(stderr, " | LPIPS %.4f", j["rgb_lpips"].get<double>());
    std::fprintf(stderr, "\n");
}

}  // namespace

void print_refine_summary(const std::string& fitdir, const pipeline::RefineSummary& s, bool emitters) {
    if (emitters)
        std::fprintf(stderr, "wrote %s/{refiner_emitters.pt, refiner_emitters_loss.csv}, added to metrics.json\n",
                     fitdir.c_str());
    else
        std::fprintf(stderr, "wrote %s/{refiner.pt, latent_refined.exr, refiner_loss.csv, metrics.json%s}\n",
                     fitdir.c_str(), s.decoded ? ", decoded_refined.png" : "");
    for (const char* key : {"rendered", "refined", "vae_roundtrip"}) show(s.metrics, key);
}

int run_refine(const RefineArgs& a) {
    const pipeline::RefineSummary s = pipeline::run_refine(a.job, console_reporter(a.quiet));
    if (!a.quiet) print_refine_summary(a.job.fitdir, s, a.job.emitters);
    return 0;
}

}  // namespace lpt::app
