// One latentpt process per fit folder at a time. Two fits (or a fit and a refine) writing one
// folder would interleave their files; the second one fails at once with a clear message
// instead. The lock is flock(2) on <folder>/.latentpt.lock: the kernel releases it when the
// process ends, however it ends, so a killed run never leaves a stale lock behind.
#pragma once
#include <string>

namespace lpt::pipeline {

class OutputLock {
public:
    /// Creates `folder` if needed and locks it; throws std::runtime_error naming the folder when
    /// another process holds it. Nested locks of one folder in one process are allowed (a fit
    /// runs its refine stage under its own lock).
    explicit OutputLock(const std::string& folder);
    ~OutputLock();
    OutputLock(const OutputLock&) = delete;
    OutputLock& operator=(const OutputLock&) = delete;

private:
    std::string m_key;
    int m_fd = -1;
};

}  // namespace lpt::pipeline
