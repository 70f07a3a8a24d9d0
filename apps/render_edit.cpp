// `latentpt render <fitdir> --edit edits.json --out outdir/`: the fitted latent scene under
// camera / light / object edits, frame by frame (pipeline::render_edits).
#include "apps/commands.h"
#include "pipeline/edit.h"
#include <iostream>

namespace lpt::app {

int run_render_edit(const RenderArgs& a) {
    pipeline::EditJob job;
    job.fitdir = a.scene;
    job.edits = a.edit;
    job.out = a.out.empty() || a.out == "render.exr" ? "edit-out" : a.out;
    job.defines = a.defines;
    if (!a.res.empty()) parse_resolution(a.res, job.width, job.height);  // latent resolution may differ from training
    if (a.spp > 0) job.spp = a.spp;
    job.seed = a.seed;
    job.reference = a.reference;
    job.ref_spp = a.ref_spp;
    job.reference_cache = a.reference_cache;
    const int frames = pipeline::render_edits(job, console_reporter(a.quiet));
    if (!a.quiet) std::cerr << "wrote " << frames << " frames to " << job.out << "\n";
    return 0;
}

}  // namespace lpt::app
