#include "pipeline/output_lock.h"
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <map>
#include <mutex>
#include <stdexcept>
#include <sys/file.h>
#include <unistd.h>

namespace lpt::pipeline {

namespace fs = std::filesystem;

namespace {

/// Folders this process holds, with how many OutputLocks hold each.
std::mutex g_mutex;
std::map<std::string, int>& held() {
    static std::map<std::string, int> h;
    return h;
}

}  // namespace

OutputLock::OutputLock(const std::string& folder) {
    fs::create_directories(folder);
    m_key = fs::canonical(folder).string();
    std::lock_guard<std::mutex> guard(g_mutex);
    if (held()[m_key]++ > 0) return;  // already ours
    const std::string path = m_key + "/.latentpt.lock";
    m_fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (m_fd < 0) {
        held().erase(m_key);
        throw std::runtime_error(path + ": cannot open the folder's lock file: " + std::strerror(errno));
    }
    if (::flock(m_fd, LOCK_EX | LOCK_NB) != 0) {
        ::close(m_fd);
        held().erase(m_key);
        throw std::runtime_error(folder + ": in use by another latentpt process (" + path +
                                 " is locked); wait for it or choose another --out");
    }
}

OutputLock::~OutputLock() {
    std::lock_guard<std::mutex> guard(g_mutex);
    if (--held()[m_key] > 0) return;
    held().erase(m_key);
    if (m_fd >= 0) ::close(m_fd);  // closing releases the flock
}

}  // namespace lpt::pipeline
