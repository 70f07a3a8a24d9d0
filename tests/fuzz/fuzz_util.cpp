#include "fuzz_util.h"
#include "core/image_io.h"
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#ifndef LPT_SOURCE_DIR
#define LPT_SOURCE_DIR "."
#endif

namespace lpt::fuzz {

namespace fs = std::filesystem;

namespace {
struct WorkDir {
    std::string path;
    WorkDir() {
        const char* tmp = std::getenv("TMPDIR");
        std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/latentpt-fuzz-XXXXXX";
        if (!::mkdtemp(pattern.data())) {
            std::perror("mkdtemp");
            std::abort();
        }
        path = pattern;
        write_assets();
    }
    /// Files the seed scenes name as @DIR@/asset.*: a mesh in each format and a texture.
    void write_assets() const {
        std::ofstream(path + "/asset.obj") << "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n";
        std::ofstream(path + "/asset.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                              "property float y\nproperty float z\nelement face 1\n"
                                              "property list uchar int vertex_indices\nend_header\n"
                                              "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        Image tex;
        tex.width = 2;
        tex.height = 2;
        tex.channels = 3;
        tex.data = {0.f, 0.5f, 1.f, 1.f, 0.f, 0.5f, 0.5f, 1.f, 0.f, 0.2f, 0.2f, 0.2f};
        write_png_display(path + "/asset.png", tex);
    }
    ~WorkDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};
}  // namespace

const std::string& work_dir() {
    static WorkDir dir;
    return dir.path;
}

std::string write_input(const std::string& name, const uint8_t* data, size_t size) {
    const std::string path = work_dir() + "/" + name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    if (!out) std::abort();
    return path;
}

std::string write_input(const std::string& name, const std::string& bytes) {
    return write_input(name, reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

std::vector<std::string> split_parts(const uint8_t* data, size_t size, size_t n) {
    const std::string all(reinterpret_cast<const char*>(data), size), sep = "\n=====\n";
    std::vector<std::string> parts;
    size_t begin = 0;
    while (parts.size() + 1 < n) {
        const size_t at = all.find(sep, begin);
        if (at == std::string::npos) break;
        parts.push_back(all.substr(begin, at - begin));
        begin = at + sep.size();
    }
    parts.push_back(all.substr(begin));
    parts.resize(n);
    return parts;
}

std::string with_dir(std::string text) {
    for (size_t at = text.find("@DIR@"); at != std::string::npos; at = text.find("@DIR@", at + 1))
        text.replace(at, 5, work_dir());
    return text;
}

void check_rejection(const std::exception& e, const std::string& name) {
    const std::string msg = e.what();
    if (std::getenv("LPT_FUZZ_SHOW")) std::fprintf(stderr, "rejected: %s\n", msg.c_str());
    const bool names_file =
        msg.find(work_dir()) != std::string::npos || (!name.empty() && msg.find(name) != std::string::npos);
    if (!msg.empty() && names_file && msg.find('\n') == std::string::npos) return;
    std::fprintf(stderr, "finding: rejection message %s:\n%s\n",
                 msg.empty()  ? "is empty"
                 : names_file ? "spans lines"
                              : "names no file",
                 msg.c_str());
    std::abort();
}

std::string bundled_scene() { return std::string(LPT_SOURCE_DIR) + "/scenes/cornell-box/scene.json"; }

}  // namespace lpt::fuzz
