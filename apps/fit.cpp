// `latentpt fit`: stage 1 of the paper's pipeline (and stage 2 unless --no-refiner), run by
// pipeline::run_fit with progress on the terminal.
#include "apps/commands.h"
#include "pipeline/fit.h"

namespace lpt::app {

int run_fit(const FitArgs& a) {
    pipeline::validate(a.job);
    const pipeline::FitSummary s = pipeline::run_fit(a.job, console_reporter(a.quiet));
    if (s.refined && !a.quiet) print_refine_summary(a.job.out, *s.refined);
    return 0;
}

}  // namespace lpt::app
