// Temporary files that an interrupt removes. Outputs are written to a hidden temporary beside
// their path and renamed into place when complete (core/image_io.cpp), so an interrupted run
// never leaves a truncated result; without this, Ctrl-C during the write left the temporary (17
// MB for a 1536² EXR) beside it. The CLI installs the handler; the Python module does not
// (Python owns SIGINT there).
#pragma once
#include <string>

namespace lpt {

/// Registers `path` as a temporary being written for as long as it lives (it does not create or
/// remove the file itself). At most 64 are registered at once; beyond that, or for a path longer
/// than 4095 bytes, one is not registered (and an interrupt leaves it, as before).
class TemporaryFile {
public:
    explicit TemporaryFile(const std::string& path);
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;

private:
    int m_slot = -1;
};

/// SIGINT, SIGTERM and SIGHUP remove every registered temporary, then end the process as the
/// signal would have (the default action, so the exit status still says which signal). A signal
/// the process inherited as ignored (nohup, a shell's background job) stays ignored.
void remove_temporaries_on_interrupt();

}  // namespace lpt
