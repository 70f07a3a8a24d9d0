#include "core/plugin_loader.h"
#include <cstdlib>
#include <dlfcn.h>
#include <filesystem>
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
    return dirs;
}

void* open_plugin(const std::string& file_name) {
    std::string tried;
    for (const std::string& dir : plugin_dirs()) {
        const fs::path path = fs::path(dir) / file_name;
        if (!fs::exists(path)) {
            tried += "\n  " + path.string() + ": not there";
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
