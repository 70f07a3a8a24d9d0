#include "pipeline/frame_cache.h"
#include "core/image_io.h"
#include <filesystem>
#include <sstream>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

/// The entry's index: on the first line the prefix of its files in `dir` and their suffixes
/// (CachedFrame::suffixes), its scores after it.
std::string index_path(const std::string& dir, const std::string& key, const std::string& name) {
    return (fs::path(dir) / (key + "_" + name + ".frame")).string();
}

}  // namespace

std::optional<std::string> take_cached_frame(const std::string& dir, const std::string& key, const std::string& name,
                                             const std::string& out_stem) {
    const std::string index = index_path(dir, key, name);
    if (!fs::exists(index)) return std::nullopt;
    const std::string text = read_file(index);
    const size_t eol = text.find('\n');
    if (eol == std::string::npos) return std::nullopt;  // not an index this code wrote
    std::istringstream line(text.substr(0, eol));
    std::string prefix;
    std::vector<std::string> suffixes;
    line >> prefix;
    for (std::string suffix; line >> suffix;) suffixes.push_back(suffix);
    const fs::path stem = fs::path(dir) / prefix;
    for (const std::string& suffix : suffixes)
        if (!fs::exists(stem.string() + suffix)) return std::nullopt;  // removed by hand: render again
    for (const std::string& suffix : suffixes) copy_file_atomic(stem.string() + suffix, out_stem + suffix);
    return text.substr(eol + 1);
}

void keep_cached_frame(const std::string& dir, const std::string& key, const std::string& name, const std::string& stem,
                       const CachedFrame& frame) {
    const std::string index = index_path(dir, key, name);
    if (fs::exists(index)) return;  // another job kept it first
    const std::string prefix = key + "_" + name + "." + writer_tag();
    std::string line = prefix;
    for (const std::string& suffix : frame.suffixes) {
        copy_file_atomic(stem + suffix, (fs::path(dir) / (prefix + suffix)).string());
        line += " " + suffix;
    }
    write_text_atomic(index, line + "\n" + frame.scores);
}

}  // namespace lpt::pipeline
