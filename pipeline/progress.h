// How a long pipeline stage talks to whoever runs it (the CLI, a test, the Python module):
// progress after every step, which may cancel the stage, and one-line notes (missing optional
// files, refused steps). The stages never print; the caller decides what to show.
#pragma once
#include <functional>
#include <stdexcept>
#include <string>

namespace lpt::pipeline {

struct StageProgress {
    const char* stage = "";   ///< "fit", "refine", "edit"
    int step = 0, total = 0;  ///< steps done (1-based) and the last step planned
    int start = 0;            ///< steps already done before this run (a resumed stage)
    double seconds = 0;       ///< since this run of the stage started (a resumed run starts again at 0)
    std::string status;       ///< the step's numbers, e.g. "loss 0.0123 (smoothed 0.0130) | lr 1.0e-03"
};

struct Reporter {
    /// After every step; returning false cancels the stage (it throws Cancelled once its
    /// last checkpoint is on disk, so a later --resume continues where it stopped).
    std::function<bool(const StageProgress&)> progress;
    std::function<void(const std::string&)> note;

    bool step(const StageProgress& p) const { return progress ? progress(p) : true; }
    void say(const std::string& text) const {
        if (note) note(text);
    }
};

/// A stage stopped because Reporter::progress returned false. No result files were written.
struct Cancelled : std::runtime_error {
    explicit Cancelled(const std::string& stage) : std::runtime_error(stage + ": cancelled") {}
};

}  // namespace lpt::pipeline
