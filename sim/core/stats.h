#pragma once
/// Wall-clock timing and peak memory, for stage summaries and manifests.
#include <chrono>
#include <cstdint>

namespace mudcrack {

class WallTimer {
public:
    WallTimer() : m_start(std::chrono::steady_clock::now()) {}
    /// Seconds since construction or the last reset().
    double seconds() const {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    }
    void reset() { m_start = std::chrono::steady_clock::now(); }

private:
    std::chrono::steady_clock::time_point m_start;
};

/// Peak resident set size of this process so far [bytes].
int64_t peak_rss_bytes();

}  // namespace mudcrack
