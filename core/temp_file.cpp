#include "core/temp_file.h"
#include <atomic>
#include <csignal>
#include <signal.h>
#include <cstring>
#include <unistd.h>

namespace lpt {

namespace {

// Fixed storage: the handler may only touch memory that no allocation moves, and lock-free atomics.
constexpr int kSlots = 64;
constexpr size_t kPathBytes = 4096;
struct Slot {
    std::atomic<bool> used{false};   ///< taken by a TemporaryFile (its path being written)
    std::atomic<bool> ready{false};  ///< path holds the whole name: the handler may unlink it
    char path[kPathBytes] = {};
};
Slot g_slots[kSlots];

extern "C" void remove_temporaries_and_reraise(int sig) {
    for (Slot& s : g_slots)
        if (s.ready.load(std::memory_order_acquire)) ::unlink(s.path);  // async-signal-safe
    std::signal(sig, SIG_DFL);
    std::raise(sig);  // pending until this handler returns, then the default action
}

}  // namespace

TemporaryFile::TemporaryFile(const std::string& path) {
    static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler reads these");
    if (path.size() >= kPathBytes) return;
    for (int i = 0; i < kSlots; ++i) {
        bool expected = false;
        if (!g_slots[i].used.compare_exchange_strong(expected, true)) continue;
        std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
        g_slots[i].ready.store(true, std::memory_order_release);
        m_slot = i;
        return;
    }
}

TemporaryFile::~TemporaryFile() {
    if (m_slot < 0) return;
    g_slots[m_slot].ready.store(false, std::memory_order_release);
    g_slots[m_slot].used.store(false, std::memory_order_release);
}

void remove_temporaries_on_interrupt() {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        struct sigaction old {};
        // nohup, and a shell's background jobs, ignore some of these: they must stay ignored
        if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;
        struct sigaction act {};
        act.sa_handler = remove_temporaries_and_reraise;
        sigemptyset(&act.sa_mask);
        act.sa_flags = SA_RESTART;
        ::sigaction(sig, &act, nullptr);
    }
}

}  // namespace lpt
