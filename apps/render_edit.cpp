// `latentpt render <fitdir> --edit edits.json --out outdir/`: the fitted latent scene under
// camera / light / object edits, frame by frame (pipeline::render_edits).
#include "apps/commands.h"
#include "pipeline/edit.h"
#include <cstdio>
#include <iostream>
#include <stdexcept>

namespace lpt::app {

namespace {

/// "A:B" or "A:B:S" with 0 <= A <= B and S >= 1 (every S-th frame from A).
void parse_frames(const std::string& s, int& first, int& last, int& step) {
    const std::optional<std::vector<int>> v = pipeline::split_integers(s, ':');
    if (!v || (v->size() != 2 && v->size() != 3) || (*v)[1] < (*v)[0] || (v->size() == 3 && (*v)[2] < 1))
        throw std::invalid_argument("--frames expects A:B or A:B:S with 0 <= A <= B and S >= 1, got '" + s + "'");
    first = (*v)[0];
    last = (*v)[1];
    step = v->size() == 3 ? (*v)[2] : 1;
}

}  // namespace

int run_render_edit(const RenderArgs& a) {
    pipeline::EditJob job;
    job.fitdir = a.scene;
    job.edits = a.edit;
    job.out = a.out.empty() || a.out == "render.exr" ? "edit-out" : a.out;
    job.defines = a.defines;
    job.sampler = a.sampler;
    if (!a.res.empty())
        parse_resolution(a.res, job.width, job.height, "--res");  // latent resolution may differ from training
    if (a.spp > 0) job.spp = a.spp;
    job.seed = a.seed;
    job.reference = a.reference;
    job.ref_spp = a.ref_spp;
    job.ref_seed = a.ref_seed;
    job.reference_cache = a.reference_cache;
    job.frame_cache = a.frame_cache;
    job.resume = a.resume;
    if (!a.frames.empty()) parse_frames(a.frames, job.first_frame, job.last_frame, job.frame_step);
    const int frames = pipeline::render_edits(job, console_reporter(a.quiet));
    if (!a.quiet) std::cerr << "wrote " << frames << " frames to " << job.out << "\n";
    return 0;
}

}  // namespace lpt::app
