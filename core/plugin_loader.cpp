#include "core/plugin_loader.h"
#include "core/plugin_interface.h"
#include "latentpt_interface_fingerprint.h"
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <dlfcn.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <stdexcept>
#include <vector>

#ifndef LPT_PLUGIN_BUILD_DIR
#define LPT_PLUGIN_BUILD_DIR ""
#endif
#ifndef LPT_PLUGIN_INSTALL_DIR
#define LPT_PLUGIN_INSTALL_DIR ""
#endif

namespace lpt {

namespace {

namespace fs = std::filesystem;

std::vector<std::string> plugin_dirs() {
    std::vector<std::string> dirs;
    if (const char* env = std::getenv("LATENTPT_PLUGIN_DIR"); env && *env) dirs.push_back(env);
    // The binary that holds this code (the executable, or the Python module): plugins are
    // installed beside it or in its ../lib/latentpt. For the executable dladdr may only know
    // argv[0] ("latentpt" found on PATH), so /proc/self/exe is asked as well.
    std::vector<fs::path> homes;
    Dl_info self{};
    if (dladdr(reinterpret_cast<void*>(&plugin_dirs), &self) && self.dli_fname && *self.dli_fname)
        homes.push_back(fs::absolute(self.dli_fname).parent_path());
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) homes.push_back(exe.parent_path());
    for (const fs::path& here : homes) {
        dirs.push_back(here.string());
        dirs.push_back((here.parent_path() / "lib" / "latentpt").string());
    }
    for (const char* d : {LPT_PLUGIN_BUILD_DIR, LPT_PLUGIN_INSTALL_DIR})
        if (*d) dirs.push_back(d);
    // The executable is usually both homes: each place once, in the order of its first mention.
    std::vector<std::string> unique;
    for (const std::string& d : dirs)
        if (std::find(unique.begin(), unique.end(), d) == unique.end()) unique.push_back(d);
    return unique;
}

// The fingerprint the plugin's file carries (plugin_interface.h), or "" when it has none. Read
// from the file, not the loaded library, so that a plugin of another build is never run.
std::string fingerprint_in_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const std::string tag = LPT_PLUGIN_INTERFACE_TAG;
    // The tag alone (a library holding this loader's code) ends in '\0', not in a value and ';'.
    for (size_t at = bytes.find(tag); at != std::string::npos; at = bytes.find(tag, at + 1)) {
        const size_t begin = at + tag.size();
        size_t end = begin;
        while (end < bytes.size() && end - begin < 64 && std::isprint(static_cast<unsigned char>(bytes[end])) &&
               bytes[end] != ';')
            ++end;
        if (end < bytes.size() && bytes[end] == ';' && end > begin) return bytes.substr(begin, end - begin);
    }
    return "";
}

// Why the plugin at path may not be opened, or "" when it may.
std::string handshake_failure(const fs::path& path) {
    const std::string theirs = fingerprint_in_file(path);
    if (theirs.empty()) return "has no interface fingerprint (built before plugins had one): rebuild it";
    if (theirs == LPT_INTERFACE_FINGERPRINT) return "";
    return "built from other headers or with another toolchain (interface " + theirs + ", this binary's " +
           LPT_INTERFACE_FINGERPRINT + "): use the plugin of this binary's build";
}

void* open_plugin(const std::string& file_name) {
    std::string tried;
    for (const std::string& dir : plugin_dirs()) {
        const fs::path path = fs::path(dir) / file_name;
        if (!fs::exists(path)) {
            tried += "\n  " + path.string() + ": not there";
            continue;
        }
        if (const std::string failure = handshake_failure(path); !failure.empty()) {
            tried += "\n  " + path.string() + ": " + failure;
            continue;
        }
        if (void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) return handle;
        tried += "\n  " + path.string() + ": " + dlerror();
    }
    throw std::runtime_error("cannot load the plugin " + file_name + " (set LATENTPT_PLUGIN_DIR); tried:" + tried);
}

}  // namespace

void* plugin_symbol(const std::string& file_name, const std::string& symbol) {
    static std::mutex mutex;
    static std::map<std::string, void*> handles;
    std::lock_guard<std::mutex> lock(mutex);
    void*& handle = handles[file_name];
    if (!handle) handle = open_plugin(file_name);
    void* address = dlsym(handle, symbol.c_str());
    if (!address) throw std::runtime_error(file_name + ": has no symbol " + symbol + " (a plugin of another build?)");
    return address;
}

}  // namespace lpt
