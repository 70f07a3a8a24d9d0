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
/// A slot's life: Free → Writing (taken, its path being copied) → Ready (the handler may unlink
/// it) → Free when its TemporaryFile ends. The handler moves Ready → Removing before it reads the
/// path (and unlinks slots another handler moved there too), and nothing moves a slot out of
/// Removing: another thread can then neither release the slot nor take it and copy a new path
/// over the one unlink is reading (the process is ending).
enum SlotState : int { Free, Writing, Ready, Removing };
struct Slot {
    std::atomic<int> state{Free};
    char path[kPathBytes] = {};
};
Slot g_slots[kSlots];

extern "C" void remove_temporaries_and_reraise(int sig) {
    for (Slot& s : g_slots) {
        // A slot another handler already claimed is unlinked here too: that handler may not
        // have reached it when this one ends the process. Its path no longer changes.
        int state = Ready;
        if (s.state.compare_exchange_strong(state, Removing, std::memory_order_acquire) || state == Removing)
            ::unlink(s.path);  // async-signal-safe
    }
    std::signal(sig, SIG_DFL);
    std::raise(sig);  // pending until this handler returns, then the default action
}

}  // namespace

TemporaryFile::TemporaryFile(const std::string& path) {
    static_assert(std::atomic<int>::is_always_lock_free, "the signal handler reads these");
    if (path.size() >= kPathBytes) return;
    for (int i = 0; i < kSlots; ++i) {
        int expected = Free;
        if (!g_slots[i].state.compare_exchange_strong(expected, Writing, std::memory_order_acquire)) continue;
        std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
        g_slots[i].state.store(Ready, std::memory_order_release);
        m_slot = i;
        return;
    }
}

TemporaryFile::~TemporaryFile() {
    if (m_slot < 0) return;
    // Fails only while the handler is removing the file: the slot then stays out of use.
    int ready = Ready;
    g_slots[m_slot].state.compare_exchange_strong(ready, Free, std::memory_order_release);
}

void remove_temporaries_on_interrupt() {
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        struct sigaction old {};
        // nohup, and a shell's background jobs, ignore some of these: they must stay ignored
        if (::sigaction(sig, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;
        struct sigaction act {};
        act.sa_handler = remove_temporaries_and_reraise;
        sigemptyset(&act.sa_mask);
        for (int other : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&act.sa_mask, other);  // no nesting
        act.sa_flags = SA_RESTART;
        ::sigaction(sig, &act, nullptr);
    }
}

}  // namespace lpt
