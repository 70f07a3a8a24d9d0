// Unedited frames shared between edit sequences (`render --edit --frame-cache`). A frame that
// shows the scene as fitted (frame 0 of every sequence: the training view) is rendered, refined,
// decoded and scored the same in every sequence of a fit, and in a convergence run at the same
// spp; the first job keeps its files and scores in the cache and the others copy them.
#pragma once
#include <optional>
#include <string>
#include <vector>

namespace lpt::pipeline {

/// One frame's entry: its files, named by `stem` + suffix (e.g. "_latent.exr"), and its scores
/// (the metrics row after its "frame,t" columns; empty without references).
struct CachedFrame {
    std::vector<std::string> suffixes;
    std::string scores;
};

/// The entry <dir>/<key>_<name>: copies its files to `out_stem` + suffix (atomically, one by one)
/// and returns its scores; nullopt when the cache has no whole entry of that key and name.
std::optional<std::string> take_cached_frame(const std::string& dir, const std::string& key, const std::string& name,
                                             const std::string& out_stem);

/// Keeps the files `stem` + suffix and the scores as the entry <dir>/<key>_<name>, unless the
/// cache has it. The entry's index is written last, so an interrupted write leaves no entry; jobs
/// keeping one frame at once write their own files (named by host and process), and the index
/// names one job's whole set.
void keep_cached_frame(const std::string& dir, const std::string& key, const std::string& name, const std::string& stem,
                       const CachedFrame& frame);

}  // namespace lpt::pipeline
