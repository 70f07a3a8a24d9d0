// A 64-bit FNV-1a fingerprint of a sequence of texts: how resumable outputs (an edited frame's
// .done key, a cached reference's header) record what they were made from, so that a later run
// tells a stale file from a current one. Not cryptographic: it guards against mistakes, not
// against anyone.
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>

namespace lpt {

class Fingerprint {
public:
    /// Adds `text` and a separator after it, so that ("ab", "c") differs from ("a", "bc").
    void add(const std::string& text) {
        for (unsigned char c : text) m_hash = (m_hash ^ c) * kPrime;
        m_hash = (m_hash ^ 0xffu) * kPrime;
    }
    /// The fingerprint as 16 lower-case hex digits.
    std::string hex() const {
        char buf[24];
        std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(m_hash));
        return buf;
    }

private:
    static constexpr uint64_t kPrime = 1099511628211ULL;
    uint64_t m_hash = 14695981039346656037ULL;
};

}  // namespace lpt
